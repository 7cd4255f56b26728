/**
 * Camera images from sensor_msgs/CompressedImage as the rosbridge JSON encoding delivers them (uint8[] data
 * as a base64 string; an array of bytes is accepted too), turned into a data: URL an <img> can show.
 */

/**
 * The image MIME type from CompressedImage.format ("jpeg", "png", "rgb8; jpeg compressed bgr8", ...).
 * @param {unknown} format
 */
export function imageMime(format) {
  const f = typeof format === 'string' ? format.toLowerCase() : '';
  if (f.includes('png')) return 'image/png';
  if (f.includes('webp')) return 'image/webp';
  return 'image/jpeg';
}

/** @param {ArrayLike<number>} bytes */
export function bytesToBase64(bytes) {
  let bin = '';
  const CHUNK = 0x8000; // String.fromCharCode takes the bytes as arguments: keep the call small
  for (let i = 0; i < bytes.length; i += CHUNK) {
    bin += String.fromCharCode.apply(null, Array.from(Array.prototype.slice.call(bytes, i, i + CHUNK)));
  }
  return btoa(bin);
}

/**
 * @param {any} msg  sensor_msgs/CompressedImage
 * @returns {string | null}  a data: URL, or null when the message holds no image
 */
export function imageSrc(msg) {
  const d = msg?.data;
  let b64 = '';
  if (typeof d === 'string') b64 = d;
  else if (d && typeof d.length === 'number' && d.length > 0) b64 = bytesToBase64(d);
  if (!b64) return null;
  return `data:${imageMime(msg?.format)};base64,${b64}`;
}

/**
 * The streams a page may show: /api/config `features.video.streams`, each { name, topic }; anything else dropped.
 * @param {unknown} streams
 * @returns {{ name: string, topic: string }[]}
 */
export function cameraStreams(streams) {
  if (!Array.isArray(streams)) return [];
  return streams
    .filter((s) => s && typeof s.topic === 'string' && s.topic)
    .map((s) => ({ name: typeof s.name === 'string' && s.name ? s.name : s.topic, topic: s.topic }));
}
