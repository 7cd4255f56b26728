// The Alarms feature's menu icon: a bell (SVG path data on a 24x24 stroked grid, see ui/Icon.svelte).
export default 'M6 16V11a6 6 0 0 1 12 0v5l2 2H4zM10 20a2 2 0 0 0 4 0';
