// The Routines feature's menu icon: a path through recorded points (SVG path data, 24x24 stroked, ui/Icon.svelte).
export default 'M5 18c3-1 3-8 7-8s3 5 7 4M5 18a1.5 1.5 0 1 0 0.01 0M12 10a1.5 1.5 0 1 0 0.01 0M19 14a1.5 1.5 0 1 0 0.01 0M5 5h6';
