// The System feature's menu icon: SVG path data on a 24x24 stroked grid (see ui/Icon.svelte).
export default 'M4 5h16v10H4zM8 19h8M12 15v4';
