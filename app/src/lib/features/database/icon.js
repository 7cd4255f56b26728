// The Database feature's menu icon: a database cylinder, SVG path data on a 24x24 stroked grid (see ui/Icon.svelte).
export default 'M4 6c0-1.7 3.6-3 8-3s8 1.3 8 3-3.6 3-8 3-8-1.3-8-3zM4 6v12c0 1.7 3.6 3 8 3s8-1.3 8-3V6M4 12c0 1.7 3.6 3 8 3s8-1.3 8-3';
