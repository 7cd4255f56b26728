// The Cameras (video) feature's menu icon: a video camera, SVG path data on a 24x24 stroked grid (see ui/Icon.svelte).
export default 'M3 7h12v10H3zM15 10.5 21 7v10l-6-3.5';
