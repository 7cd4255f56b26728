// The Process feature's menu icon: a play triangle in a cycle arrow (SVG path data, 24x24 stroked, ui/Icon.svelte).
export default 'M20 12a8 8 0 1 1-2.34-5.66M20 4v4h-4M10 9v6l5-3z';
