// The Manual motion feature's menu icon: a robot arm, SVG path data on a 24x24 stroked grid (see ui/Icon.svelte).
export default 'M4 21h10M9 21v-3M9 18 6.5 11.5 13 6l4 4M17 10l2.5 1.5M17 10l1-3M6.5 11.5a1.5 1.5 0 1 0 0.01 0';
