// The Recorder feature's menu icon: a flight recorder box with its record dot and a trace (SVG path data on a 24x24
// stroked grid, see ui/Icon.svelte).
export default 'M3 6h18v12H3zM6 12a2 2 0 1 0 4 0a2 2 0 1 0-4 0M13 13l2-3 2 4 2-2';
