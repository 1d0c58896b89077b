// Face colours of the surface: a zone's colour, or a scalar (displacement, local volume change,
// contact force) on a blue-white-red or white-red scale. Every face gets one colour (flat
// shading), written into the three vertices of that face.

const ZONES = [[0.27, 0.51, 0.71], [0.87, 0.49, 0.19], [0.35, 0.63, 0.33], [0.78, 0.3, 0.33], [0.58, 0.45, 0.7],
  [0.55, 0.4, 0.33], [0.85, 0.55, 0.73], [0.5, 0.5, 0.5], [0.74, 0.74, 0.29], [0.27, 0.71, 0.76]];
const NONE = [0.8, 0.8, 0.78];

// t in [0, 1] on white-to-red; s in [-1, 1] on blue-white-red.
const heat = (t) => [1, 1 - 0.8 * t, 1 - 0.85 * t];
const diverging = (s) => (s >= 0 ? heat(s) : [1 + 0.8 * s, 1 + 0.5 * s, 1]);

function faceScalars(mode, meta, frame) {
  const faces = meta.faces, F = faces.length / 3;
  const out = new Float32Array(F);
  if (mode === "volume") return frame.volume;
  for (let f = 0; f < F; ++f) {
    let sum = 0;
    for (let c = 0; c < 3; ++c) {
      const n = faces[3 * f + c];
      if (mode === "contact") sum += frame.contact ? frame.contact[n] : 0;
      else sum += Math.hypot(frame.positions[3 * n] - meta.rest[3 * n], frame.positions[3 * n + 1] - meta.rest[3 * n + 1], frame.positions[3 * n + 2] - meta.rest[3 * n + 2]);
    }
    out[f] = sum / 3;
  }
  return out;
}

// Fills `colours` (9 per face) and returns the scale's range ([lo, hi]; null for zones).
export function colourFaces(colours, mode, meta, frame) {
  const F = meta.faces.length / 3;
  const put = (f, rgb) => { for (let c = 0; c < 3; ++c) colours.set(rgb, 9 * f + 3 * c); };
  if (mode === "zone") {
    for (let f = 0; f < F; ++f) put(f, meta.face_zone[f] >= 0 ? ZONES[meta.face_zone[f] % ZONES.length] : NONE);
    return null;
  }
  const s = faceScalars(mode, meta, frame);
  let hi = 0;
  for (let f = 0; f < F; ++f) hi = Math.max(hi, Math.abs(s[f]));
  const scale = hi > 0 ? 1 / hi : 0;
  for (let f = 0; f < F; ++f) put(f, mode === "volume" ? diverging(s[f] * scale) : heat(s[f] * scale));
  return mode === "volume" ? [-hi, hi] : [0, hi];
}

const units = { displacement: "m", volume: "(V/V₀ − 1 of the face's tet)", contact: "N" };

// The legend: one item per zone with its colour, or the scalar's range.
export function legendItems(mode, range, meta) {
  if (mode === "zone") {
    if (!meta.zones.length) return [{ text: "no zones" }];
    return meta.zones.map((z, i) => ({ text: z, rgb: ZONES[i % ZONES.length] }));
  }
  return [{ text: `${mode}: ${range[0].toPrecision(3)} … ${range[1].toPrecision(3)} ${units[mode]}` }];
}
