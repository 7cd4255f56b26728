// The Inspect feature's menu icon: log lines under a magnifier (SVG path data on a 24x24 stroked grid, see
// ui/Icon.svelte).
export default 'M4 5h14M4 9h9M4 13h5M4 17h4M11 15a4 4 0 1 0 8 0a4 4 0 1 0-8 0M18 18l3 3';
