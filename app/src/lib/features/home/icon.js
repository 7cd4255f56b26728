// The Home feature's menu icon: SVG path data on a 24x24 stroked grid (see ui/Icon.svelte).
export default 'M3 11.5 12 4l9 7.5V20a1 1 0 0 1-1 1h-5v-6H9v6H4a1 1 0 0 1-1-1z';
