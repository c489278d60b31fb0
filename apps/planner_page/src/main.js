// The planner page: loads a patient and the average chest from `pectus serve`, then every frame the bar
// changed deforms the chest from the basis (basis.js) and shows the live figures; the exact figures (RMS,
// max and central difference to the average chest, the lift solved) come from the server's plan, which is
// `pectus plan`'s C++ (MakeNussPlan). Views draw from the one state (state.js).
import * as THREE from 'three';
import { getBinary, getJson, postJson } from './api.js';
import { deform, liftPerNewton, makeBasis, onSternum } from './basis.js';
import { drawColourBar } from './colormap.js';
import { renderPanel } from './panel.js';
import { Scene } from './scene.js';
import { Trainer, renderTrainerPanel } from './trainer.js';
import { positionMm, set, state, subscribe } from './state.js';

// When the page's start steps ended, ms after the page started loading (performance.now()'s origin).
const startTimings = { module: performance.now() };
const scene = new Scene(document.getElementById('scene'));
const trainer = new Trainer(scene);
startTimings.webgl = performance.now();
let basis = null;
let drawnBar = null; // the bar the scene shows
let planTimer = 0, planSerial = 0;

// ---- data ----------------------------------------------------------------------------------------------
async function loadPatient(id) {
  set({ busy: `loading patient ${id} (its response basis takes a few seconds the first time)…`, error: '' });
  const path = `/api/patients/${encodeURIComponent(id)}`;
  const info = await getJson(path);
  const [bone, skin, landmarks, table] = await Promise.all(['bone', 'skin', 'landmarks', 'basis'].map((w) => getBinary(`${path}/${w}`)));
  startTimings.patient_downloaded ??= performance.now();
  basis = makeBasis(info, table);
  scene.setPatient(info, bone, skin, landmarks);
  startTimings.scene_built ??= performance.now();
  drawnBar = null;
  ++planSerial; // an answer still coming is for the patient before
  set({ patientId: id, info, plan: null, planFor: null, search: null, busy: '' });
}

/// The server's exact figures for the current bar (/api/score: scenarios A and B from the patient's exact
/// basis, scored by pectus plan's C++; milliseconds). One request at a time: while the bar moves, the next
/// goes out as soon as the last answer is in, for where the bar is then, so the colour map and the figures
/// follow a drag at the server's pace; only the latest answer is kept.
let planInFlight = false, planWanted = false;
function requestPlan(delay = 0) {
  clearTimeout(planTimer);
  if (delay > 0) {
    planTimer = setTimeout(() => requestPlan(0), delay);
    return;
  }
  if (planInFlight) {
    planWanted = true;
    return;
  }
  planInFlight = true;
  planWanted = false;
  const serial = ++planSerial;
  const bar = { ...state.bar };
  postJson('/api/score', planBody(bar))
    .then((plan) => serial === planSerial && set({ plan, planFor: bar, error: '' }))
    .catch((e) => serial === planSerial && set({ error: e.message }))
    .finally(() => {
      planInFlight = false;
      // While dragging, at most about fifteen a second: each answer recolours the map, and answers come
      // faster than frames.
      if (planWanted) requestPlan(state.dragging ? 60 : 0);
    });
}
function planBody(bar, search) {
  const mm = bar.position * state.info.sternal_length_mm;
  const body = {
    patient: state.patientId,
    bar: { position: bar.position, position_in_mm: false, force_n: bar.force },
    compare: { position: Math.max(0, mm - state.compareMm), position_in_mm: true, force_n: bar.force },
  };
  if (search) body.search = search;
  return body;
}

async function runSearch() {
  set({ busy: 'searching the best placement…' });
  try {
    const plan = await postJson('/api/plan', planBody(state.bar, { positions: 8, forces: 12, refinements: 6 }));
    set({ search: plan.search, busy: '' });
  } catch (e) {
    set({ busy: '', error: e.message });
  }
}

// ---- the bar ---------------------------------------------------------------------------------------------
/// Moves the bar (fraction of the sternal length, N); the scene follows on the next frame.
function setBar(patch) {
  const bar = { ...state.bar, ...patch };
  bar.position = Math.min(Math.max(bar.position, 0), 1);
  bar.force = Math.min(Math.max(bar.force, 1), 3000);
  if (basis && !onSternum(basis, bar.position * state.info.sternal_length_mm)) return;
  set({ bar });
  requestPlan();
}
/// The force that lifts the sternum by `liftMm` at the current position (from the basis).
function setLift(liftMm) {
  const perN = liftPerNewton(basis, positionMm());
  if (perN > 0) setBar({ force: liftMm / perN });
}

// The live figures and the deformation, from the basis: only when the bar moved since the last frame.
function update() {
  if (!basis || !state.info) return;
  const bar = state.bar, view = state.view;
  // The ribcage and the skin are deformed while shown (a part shown again is brought up to date).
  const d = drawnBar;
  if (d && d.position === bar.position && d.force === bar.force && (d.bone || !view.bone) && (d.skin || !view.skin)) return;
  const mm = positionMm();
  const t0 = performance.now();
  const lift = deform(basis, mm, bar.force, basis.boneRows + basis.skinRows, scene.landmarkDisplacement);
  if (view.bone) deform(basis, mm, bar.force, 0, scene.boneDisplacement);
  if (view.skin) deform(basis, mm, bar.force, basis.boneRows, scene.skinDisplacement);
  const updateMs = performance.now() - t0;
  scene.applyDeformation(mm, view, state.dragging);
  drawnBar = { ...bar, bone: view.bone, skin: view.skin };
  const perN = lift / bar.force;
  set({
    live: {
      positionMm: mm,
      liftMm: lift,
      liftPerN: perN,
      forceToLift: perN > 0 ? state.info.depression_mm / perN : NaN,
      beyondLinear: lift > state.info.linear_range_lift_mm,
      updateMs,
      position: bar.position,
      force: bar.force,
    },
  });
}

// ---- views ---------------------------------------------------------------------------------------------
subscribe((s) => {
  scene.show(s.view);
  document.getElementById('status').textContent = s.error ? `error: ${s.error}` : s.busy || (s.plan ? 'ready' : 'scoring…');
});
let shownPlan = null, shownMap = '';
subscribe((s) => {
  // The colour map: the server's difference of scenario A to the average chest, on one scale.
  if (!s.plan || !scene.predicted) return;
  if (shownPlan === s.plan && shownMap === s.view.colormap) return;
  shownPlan = s.plan;
  shownMap = s.view.colormap;
  const a = s.plan.scenarios[0];
  const limit = Math.max(1, Math.ceil(Math.max(a.score.max_abs_mm, 1)));
  scene.setPredicted(a.difference_mm, limit, s.view.colormap);
  scene.predicted.userData.ready = true;
  scene.show(s.view);
  drawColourBar(document.getElementById('colorbar'), s.view.colormap, limit);
});
renderPanel(document.getElementById('panel'), { setBar, setLift, runSearch, loadPatient, requestPlan, exportPlan, exportPng, exportPly, loadPlan });
trainer.placeBar = setBar;
renderTrainerPanel(document.getElementById('trainer'), trainer);

// ---- keyboard and dragging ---------------------------------------------------------------------------------
window.addEventListener('keydown', (e) => {
  if (e.target instanceof HTMLInputElement && e.target.type !== 'range') return;
  if (e.target instanceof HTMLSelectElement) return;
  // While a trainer session runs the keys move its device.
  if (trainer.key(e)) {
    e.preventDefault();
    return;
  }
  const step = e.shiftKey ? 10 : 1;
  const L = state.info?.sternal_length_mm ?? 1;
  const moves = {
    ArrowUp: { position: state.bar.position - step / L },
    ArrowDown: { position: state.bar.position + step / L },
    ArrowRight: { force: state.bar.force + 5 * step },
    ArrowLeft: { force: state.bar.force - 5 * step },
  };
  if (moves[e.key]) {
    e.preventDefault();
    setBar(moves[e.key]);
  }
});
{
  const canvas = scene.renderer.domElement;
  const ray = new THREE.Raycaster();
  let drag = null;
  canvas.addEventListener('pointerdown', (e) => {
    if (!scene.bar) return;
    const r = canvas.getBoundingClientRect();
    ray.setFromCamera(new THREE.Vector2(((e.clientX - r.left) / r.width) * 2 - 1, -((e.clientY - r.top) / r.height) * 2 + 1), scene.camera);
    if (ray.intersectObject(scene.bar).length === 0 && !e.shiftKey) return;
    drag = { y: e.clientY, position: state.bar.position, mmPerPixel: (scene.camera.position.distanceTo(scene.controls.target) * Math.tan((scene.camera.fov * Math.PI) / 360) * 2) / r.height };
    scene.controls.enabled = false;
    scene.setMoving(true);
    set({ dragging: true });
    canvas.setPointerCapture(e.pointerId);
  });
  // The bar follows the pointer once per frame (loop()), however many moves arrive in between.
  canvas.addEventListener('pointermove', (e) => {
    if (!drag) return;
    draggedTo = drag.position + ((e.clientY - drag.y) * drag.mmPerPixel) / state.info.sternal_length_mm;
  });
  canvas.addEventListener('pointerup', () => {
    if (draggedTo !== null) setBar({ position: draggedTo });
    draggedTo = null;
    if (drag && scene.setMoving(false)) dirty = true;
    if (drag) {
      set({ dragging: false });
      drawnBar = null; // drawn again at rest, with its normals
    }
    drag = null;
    scene.controls.enabled = true;
  });
  // Turning the camera: the same lighter frames while it moves.
  scene.controls.addEventListener('start', () => scene.setMoving(true));
  scene.controls.addEventListener('end', () => scene.setMoving(false) && (dirty = true));
}

// ---- export and load -------------------------------------------------------------------------------------
function download(name, blob) {
  const a = document.createElement('a');
  a.href = URL.createObjectURL(blob);
  a.download = name;
  a.click();
  setTimeout(() => URL.revokeObjectURL(a.href), 1000);
}
/// The plan of the bar shown as JSON: `pectus plan --report`'s figures, made by the server's MakeNussPlan
/// (direct solves, force to lift, registration) for scenarios A and B, with the patient.
async function planJson() {
  if (!state.info) return null;
  set({ busy: 'making the plan…' });
  try {
    const { before, scenarios, ...rest } = await postJson('/api/plan', planBody(state.bar));
    const strip = ({ difference_mm, ...keep }) => keep;
    return JSON.stringify({ ...rest, before: strip(before), scenarios: scenarios.map(strip), patient: state.patientId }, null, 1);
  } finally {
    set({ busy: '' });
  }
}
async function exportPlan() {
  try {
    const text = await planJson();
    if (text) download(`plan_${state.patientId}.json`, new Blob([text], { type: 'application/json' }));
  } catch (e) {
    set({ error: e.message });
  }
}
function exportPng() {
  trainer.render();
  scene.renderer.domElement.toBlob((blob) => download(`planner_${state.patientId}.png`, blob));
}
/// The predicted chest (scenario A, the average chest's frame) as ASCII PLY with its difference, mm.
function plyText() {
  const p = scene.predicted?.geometry;
  if (!p || !state.plan) return null;
  const v = p.attributes.position.array, f = p.index.array, d = state.plan.scenarios[0].difference_mm;
  const lines = ['ply', 'format ascii 1.0', `element vertex ${v.length / 3}`, 'property float x', 'property float y', 'property float z', 'property float difference_mm', `element face ${f.length / 3}`, 'property list uchar int vertex_indices', 'end_header'];
  for (let i = 0; i < v.length / 3; ++i) lines.push(`${v[3 * i]} ${v[3 * i + 1]} ${v[3 * i + 2]} ${d[i] ?? 'nan'}`);
  for (let i = 0; i < f.length / 3; ++i) lines.push(`3 ${f[3 * i]} ${f[3 * i + 1]} ${f[3 * i + 2]}`);
  return lines.join('\n') + '\n';
}
function exportPly() {
  const text = plyText();
  if (text) download(`predicted_chest_${state.patientId}.ply`, new Blob([text], { type: 'text/plain' }));
}
/// Loads a plan JSON (exported here or `pectus plan --report`): its patient and scenario A's bar.
async function loadPlan(text) {
  const plan = JSON.parse(text);
  const a = plan.scenarios?.[0]?.bar;
  if (!a || typeof a.position !== 'number' || typeof a.force_n !== 'number') throw new Error('not a plan: no scenarios[0].bar');
  const id = String(plan.patient ?? state.patientId);
  if (id !== state.patientId) await loadPatient(id);
  const position = a.position_in_mm ? a.position / state.info.sternal_length_mm : a.position;
  setBar({ position, force: a.force_n });
}

// ---- start ---------------------------------------------------------------------------------------------
async function start() {
  try {
    startTimings.script = performance.now();
    const [patients, average] = await Promise.all([getJson('/api/patients'), getJson('/api/average')]);
    scene.anterior = average.anterior;
    scene.setAverage(average, await getBinary('/api/average/mesh'));
    startTimings.average = performance.now();
    set({ patients, average });
    const wanted = new URLSearchParams(location.search).get('patient');
    await loadPatient(patients.some((p) => p.id === wanted) ? wanted : patients[0].id);
    requestPlan(0);
  } catch (e) {
    set({ busy: '', error: e.message });
  }
}
// Frames are drawn when something changed (the state, the camera, the size), not continuously: an idle
// page costs nothing.
let dirty = true, renders = 0;
let draggedTo = null; // where the pointer has dragged the bar since the last frame (fraction), or null
subscribe(() => (dirty = true));
scene.controls.addEventListener('change', () => (dirty = true));
new ResizeObserver(() => (dirty = true)).observe(document.getElementById('scene'));
function loop() {
  if (draggedTo !== null) {
    setBar({ position: draggedTo });
    draggedTo = null;
  }
  update();
  trainer.frame();
  if (dirty) {
    dirty = false;
    trainer.render();
    ++renders;
  }
  requestAnimationFrame(loop);
}
// The first frame with the patient, ms after the page started loading (performance.now()'s origin).
let firstFrameMs = null;
start().then(() => {
  update();
  trainer.render();
  firstFrameMs = performance.now();
});
requestAnimationFrame(loop);

// For tests and for a user's console: the state, the actions, the basis evaluation and the exports.
window.pectus = { state, set, scene, trainer, setBar, setLift, loadPatient, loadPlan, planJson, plyText, runSearch,
  firstFrameMs: () => firstFrameMs,
  startTimings: () => ({ ...startTimings, first_frame: firstFrameMs }),
  /// Mean times of a frame whose bar moved, ms: the deformation from the basis, moving the meshes (and
  /// their normals), and drawing (to the end of the GPU's work).
  timeFrames: (n) => {
    const gl = scene.renderer.getContext();
    const t = { deform: 0, apply: 0, draw: 0 };
    const mm = positionMm();
    for (let i = 0; i < n; ++i) {
      const at = mm + (i % 10) * 0.05;
      let t0 = performance.now();
      deform(basis, at, state.bar.force, 0, scene.boneDisplacement);
      deform(basis, at, state.bar.force, basis.boneRows, scene.skinDisplacement);
      deform(basis, at, state.bar.force, basis.boneRows + basis.skinRows, scene.landmarkDisplacement);
      let t1 = performance.now();
      t.deform += t1 - t0;
      scene.applyDeformation(at);
      t0 = performance.now();
      t.apply += t0 - t1;
      scene.render();
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));
      t.draw += performance.now() - t0;
    }
    drawnBar = null;
    return Object.fromEntries(Object.entries(t).map(([k, v]) => [k, v / n]));
  },
  setMoving: (moving) => scene.setMoving(moving),
  renders: () => renders,
  deformSkin: (mm, force) => {
    const out = new Float32Array(basis.skinRows);
    deform(basis, mm, force, basis.boneRows, out);
    return Array.from(out, (d, i) => d + scene.skinRest[i]);
  },
  liftAt: (mm, force) => liftPerNewton(basis, mm) * force,
  skinPositions: () => scene.skin.geometry.attributes.position.array,
  /// Mean time of the per-frame deformation (bone, skin, landmarks from the basis), ms.
  timeUpdate: (n) => {
    const mm = positionMm();
    const t0 = performance.now();
    for (let i = 0; i < n; ++i) {
      deform(basis, mm + (i % 10) * 0.05, state.bar.force, 0, scene.boneDisplacement);
      deform(basis, mm + (i % 10) * 0.05, state.bar.force, basis.boneRows, scene.skinDisplacement);
      deform(basis, mm + (i % 10) * 0.05, state.bar.force, basis.boneRows + basis.skinRows, scene.landmarkDisplacement);
    }
    drawnBar = null;
    return (performance.now() - t0) / n;
  },
};
