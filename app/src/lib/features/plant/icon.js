// The Plant feature's menu icon: a factory hall with saw-tooth roof and a chimney (SVG path data on a 24x24 stroked
// grid, see ui/Icon.svelte).
export default 'M3 21V11l5 3v-3l5 3v-3l5 3V4h3v17zM7 17h2M12 17h2';
