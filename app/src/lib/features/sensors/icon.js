// The Sensors feature's menu icon: a graph line on axes, SVG path data on a 24x24 stroked grid (see ui/Icon.svelte).
export default 'M3 3v18h18M6 15l4-5 4 3 5-7';
