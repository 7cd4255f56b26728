// The 3D view (scene) feature's menu icon: a cube in perspective, SVG path data on a 24x24 stroked grid (see ui/Icon.svelte).
export default 'M12 3 20 7.5v9L12 21l-8-4.5v-9zM12 12l8-4.5M12 12v9M12 12 4 7.5';
