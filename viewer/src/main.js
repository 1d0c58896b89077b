// The page of `isochor view` (tools/view.py serves it; `--export` writes it with its data):
// a run's surface in WebGL, a timeline, colours by zone, displacement, local volume change and
// contact force, the colliders, and the run's charts linked to the timeline. Frames come one at a
// time on demand (/api/frame/K, or data/frame_K.js in an exported folder), so a long run opens as
// fast as a short one; while the run is being written, the page asks for its meta again and grows.
import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import { drawChart, timeAt } from "./charts.js";
import { colourFaces, legendItems } from "./colours.js";
import { boneObject, colliderObject, poseBone, poseCollider } from "./colliders.js";

const exported = typeof window.ISOCHOR_META === "object";
const params = new URLSearchParams(location.search);
const $ = (id) => document.getElementById(id);

// What went wrong in the page itself (a test reads it from #state with the view's projection).
const pageErrors = [];
window.addEventListener("error", (e) => pageErrors.push(String(e.message)));
window.addEventListener("unhandledrejection", (e) => pageErrors.push(String(e.reason)));

const state = { meta: null, frame: 0, shown: -1, playing: false, cache: new Map(), pending: new Map(), colour: params.get("colour") || "zone" };
let renderer, scene, camera, controls, mesh, colliderObjects = [], boneObjects = [];

function fail(message) {
  const box = $("error");
  box.hidden = false;
  box.textContent = message;
  $("state").textContent = JSON.stringify({ error: message });
}

async function loadMeta() {
  if (exported) return window.ISOCHOR_META;
  const r = await fetch("api/meta", { cache: "no-store" });
  const body = await r.json().catch(() => ({ error: `the server answered ${r.status} without a reason` }));
  if (!r.ok || body.error) throw new Error(body.error || `the server answered ${r.status}`);
  return body;
}

// One frame: {time, positions (S*3), volume (F), contact (S or null), poses (C*12), scales (C),
// bones (B*12)}.
function decodeFrame(buffer, meta) {
  const S = meta.rest.length / 3, F = meta.face_zone.length, C = meta.colliders.length;
  const time = new DataView(buffer).getFloat64(0, true);
  const f = new Float32Array(buffer, 8);
  let at = 0;
  const take = (n) => f.subarray(at, (at += n));
  const positions = take(3 * S), volume = take(F);
  const contact = meta.has_contact ? take(S) : null;
  return { time, positions, volume, contact, poses: take(12 * C), scales: take(C), bones: take(12 * meta.bones.length) };
}

function fetchFrame(k) {
  if (state.cache.has(k)) return Promise.resolve(state.cache.get(k));
  if (state.pending.has(k)) return state.pending.get(k);
  const p = (exported ? loadExportedFrame(k) : fetch(`api/frame/${k}`, { cache: "no-store" }).then(async (r) => {
    if (!r.ok) throw new Error((await r.json().catch(() => ({}))).error || `frame ${k}: the server answered ${r.status}`);
    return r.arrayBuffer();
  })).then((buffer) => {
    const frame = decodeFrame(buffer, state.meta);
    state.pending.delete(k);
    state.cache.set(k, frame);
    if (state.cache.size > 400) state.cache.delete(state.cache.keys().next().value);
    return frame;
  });
  state.pending.set(k, p);
  return p;
}

// An exported folder: frame K is data/frame_K.js, which calls ISOCHOR_FRAME(K, base64).
const exportedWaiting = new Map();
window.ISOCHOR_FRAME = (k, b64) => {
  const bytes = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
  const resolve = exportedWaiting.get(k);
  exportedWaiting.delete(k);
  if (resolve) resolve(bytes.buffer);
};
function loadExportedFrame(k) {
  const frames = state.meta.exported_frames;
  const nearest = frames.reduce((a, b) => (Math.abs(b - k) < Math.abs(a - k) ? b : a), frames[0]);
  return new Promise((resolve, reject) => {
    exportedWaiting.set(nearest, resolve);
    const s = document.createElement("script");
    s.src = `data/frame_${nearest}.js`;
    s.onload = () => s.remove();
    s.onerror = () => reject(new Error(`data/frame_${nearest}.js is missing from the exported folder`));
    document.head.appendChild(s);
  });
}

// The canvas's size: the view's, or ?size=WxH fixed (a test's screenshots then share one camera
// whatever the window does).
function viewSize() {
  const fixed = /^(\d+)x(\d+)$/.exec(params.get("size") || "");
  return fixed ? [Number(fixed[1]), Number(fixed[2])] : [$("view").clientWidth, $("view").clientHeight];
}

// The scene, its camera framing `positions` (the first frame shown: a body may start away from
// its rest shape).
function setUpScene(meta, positions) {
  const view = $("view");
  renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  renderer.setSize(...viewSize());
  renderer.setClearColor(0xf4f4f2);
  view.appendChild(renderer.domElement);
  scene = new THREE.Scene();
  scene.add(new THREE.HemisphereLight(0xffffff, 0x777766, 2.2));
  const sun = new THREE.DirectionalLight(0xffffff, 1.6);
  scene.add(sun);

  const F = meta.face_zone.length;
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute("position", new THREE.BufferAttribute(new Float32Array(9 * F), 3));
  geometry.setAttribute("color", new THREE.BufferAttribute(new Float32Array(9 * F), 3));
  mesh = new THREE.Mesh(geometry, new THREE.MeshStandardMaterial({ vertexColors: true, flatShading: true, roughness: 0.8, side: THREE.DoubleSide }));
  scene.add(mesh);

  // The camera: up as the run says, looking at the rest shape from the side, a little above.
  const up = new THREE.Vector3(...meta.up).normalize();
  const box = new THREE.Box3().setFromArray(positions);
  const centre = box.getCenter(new THREE.Vector3());
  const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-6);
  const side = new THREE.Vector3(1, 0, 0).addScaledVector(up, -up.x).normalize();
  if (side.lengthSq() < 0.5) side.set(0, 1, 0).addScaledVector(up, -up.y).normalize();
  const direction = side.clone().cross(up).multiplyScalar(-1).add(side.clone().multiplyScalar(0.6)).addScaledVector(up, 0.45).normalize();
  const [width, height] = viewSize();
  camera = new THREE.PerspectiveCamera(35, width / height, radius / 100, radius * 100);
  camera.up.copy(up);
  camera.position.copy(centre).addScaledVector(direction, radius / Math.sin((17.5 * Math.PI) / 180) * 1.15);
  camera.lookAt(centre);
  sun.position.copy(camera.position).addScaledVector(up, radius * 2);
  controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(centre);
  controls.update();
  controls.addEventListener("change", render);

  colliderObjects = meta.colliders.map((c) => colliderObject(THREE, c, radius, centre));
  colliderObjects.forEach((o) => o && scene.add(o));
  boneObjects = meta.bones.map((b) => boneObject(THREE, b, radius));
  boneObjects.forEach((o) => scene.add(o));
  window.addEventListener("resize", () => {
    const [w, h] = viewSize();
    renderer.setSize(w, h);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    render();
  });
}

function showFrame(frame) {
  const meta = state.meta;
  const faces = meta.faces, F = faces.length / 3;
  const position = mesh.geometry.attributes.position.array;
  for (let f = 0; f < F; ++f)
    for (let c = 0; c < 3; ++c) {
      const n = faces[3 * f + c];
      position.set(frame.positions.subarray(3 * n, 3 * n + 3), 9 * f + 3 * c);
    }
  mesh.geometry.attributes.position.needsUpdate = true;
  mesh.geometry.computeVertexNormals();
  mesh.geometry.computeBoundingSphere();
  const range = colourFaces(mesh.geometry.attributes.color.array, state.colour, meta, frame);
  mesh.geometry.attributes.color.needsUpdate = true;
  showLegend(legendItems(state.colour, range, meta));
  colliderObjects.forEach((o, c) => o && poseCollider(o, meta.colliders[c], frame.poses.subarray(12 * c, 12 * c + 12), frame.scales[c]));
  boneObjects.forEach((o, b) => poseBone(o, frame.bones.subarray(12 * b, 12 * b + 12)));
  $("clock").textContent = `frame ${state.frame} / ${meta.frames - 1}   t = ${frame.time.toFixed(4)} s`;
  render();
  drawCharts(frame.time);
}

function showLegend(items) {
  const legend = $("legend");
  legend.replaceChildren(...items.map(({ text, rgb }) => {
    const span = document.createElement("span");
    span.textContent = rgb ? `■ ${text}  ` : text;
    if (rgb) span.style.color = `rgb(${rgb.map((c) => Math.round(255 * c)).join(",")})`;
    return span;
  }));
}

function render() {
  if (!renderer) return;
  renderer.render(scene, camera);
  const vp = camera.projectionMatrix.clone().multiply(camera.matrixWorldInverse);
  const rect = renderer.domElement.getBoundingClientRect();
  $("state").textContent = JSON.stringify({ ready: true, frame: state.frame, frames: state.meta.frames, status: state.meta.status, colour: state.colour, view_projection: vp.elements, left: rect.left, top: rect.top, width: renderer.domElement.width, height: renderer.domElement.height, errors: pageErrors });
}

function drawCharts(time) {
  for (const canvas of document.querySelectorAll("#charts canvas")) drawChart(canvas, state.meta.charts[canvas.dataset.series], time, state.meta.time_end);
}

async function goTo(k) {
  const meta = state.meta;
  state.frame = Math.max(0, Math.min(meta.frames - 1, k));
  $("timeline").value = state.frame;
  const wanted = state.frame;
  try {
    const frame = await fetchFrame(wanted);
    if (wanted === state.frame) {
      state.shown = wanted;
      showFrame(frame);
    }
    if (state.playing) for (let j = 1; j <= 4; ++j) if (wanted + j < meta.frames) fetchFrame(wanted + j).catch(() => {});
  } catch (e) {
    state.playing = false;
    fail(`${meta.file}: ${e.message}`);
  }
}

function play() {
  state.playing = !state.playing;
  $("play").textContent = state.playing ? "❚❚" : "▶";
  let last = performance.now();
  const tick = (now) => {
    if (!state.playing) return;
    if (now - last > 33 && state.shown === state.frame) {
      last = now;
      if (state.frame + 1 >= state.meta.frames) state.playing = false, ($("play").textContent = "▶");
      else goTo(state.frame + 1);
    }
    requestAnimationFrame(tick);
  };
  requestAnimationFrame(tick);
}

function wireControls() {
  $("timeline").max = state.meta.frames - 1;
  $("timeline").addEventListener("input", (e) => goTo(Number(e.target.value)));
  $("prev").addEventListener("click", () => goTo(state.frame - 1));
  $("next").addEventListener("click", () => goTo(state.frame + 1));
  $("play").addEventListener("click", play);
  $("colour").value = state.colour;
  $("colour").addEventListener("change", (e) => {
    state.colour = e.target.value;
    goTo(state.frame);
  });
  for (const canvas of document.querySelectorAll("#charts canvas"))
    canvas.addEventListener("click", (e) => {
      const t = timeAt(canvas, e.offsetX, state.meta.time_end);
      goTo(Math.round((t / Math.max(state.meta.time_end, 1e-300)) * (state.meta.frames - 1)));
    });
  window.addEventListener("keydown", (e) => {
    if (e.key === "ArrowRight") goTo(state.frame + 1);
    if (e.key === "ArrowLeft") goTo(state.frame - 1);
    if (e.key === " ") play();
  });
}

// A run still being written: its meta again every 2 s until it is not "running".
function followGrowth() {
  if (exported || state.meta.status !== "running") return;
  setTimeout(async () => {
    try {
      const meta = await loadMeta();
      Object.assign(state.meta, { frames: meta.frames, status: meta.status, charts: meta.charts, time_end: meta.time_end });
      $("timeline").max = meta.frames - 1;
      $("title").textContent = `${meta.file} (${meta.status}, ${meta.frames} frames)`;
      drawCharts(state.cache.get(state.shown)?.time ?? 0);
    } catch (e) {
      fail(`${state.meta.file}: ${e.message}`);
      return;
    }
    followGrowth();
  }, 2000);
}

async function start() {
  try {
    state.meta = await loadMeta();
  } catch (e) {
    fail(`The run could not be read: ${e.message}`);
    return;
  }
  const meta = state.meta;
  document.title = `${meta.file} — isochor view`;
  $("title").textContent = `${meta.file} (${meta.status}, ${meta.frames} frames)`;
  if (!meta.has_contact) $("colour").querySelector('option[value="contact"]').disabled = true;
  const first = Math.max(0, Math.min(meta.frames - 1, Number(params.get("frame") || 0)));
  try {
    setUpScene(meta, (await fetchFrame(first)).positions);
  } catch (e) {
    fail(`${meta.file}: ${e.message}`);
    return;
  }
  wireControls();
  await goTo(first);
  // ?steps=N presses "next frame" N times once the first frame is shown (as a user would).
  for (let i = 0; i < Number(params.get("steps") || 0); ++i) {
    $("next").click();
    await state.pending.get(state.frame);
  }
  followGrowth();
}

start();
