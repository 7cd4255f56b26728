// The Parameters feature's menu icon: three sliders (SVG path data, 24x24 stroked, ui/Icon.svelte).
export default 'M4 6h16M4 12h16M4 18h16M8 4v4M15 10v4M10 16v4';
