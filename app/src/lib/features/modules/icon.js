// The Modules feature's menu icon: stacked blocks (SVG path data on a 24x24 stroked grid, see ui/Icon.svelte).
export default 'M4 4h7v7H4zM13 4h7v7h-7zM4 13h7v7H4zM13 16.5h7M16.5 13v7';
