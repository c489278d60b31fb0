// The side panel: the controls (patient, bar position and force or wanted lift, view), the live figures
// from the basis, the server's exact figures for scenarios A and B, the best-placement search with its
// map, export and load. Drawn from the state after every change.
import { colormapNames, colour } from './colormap.js';
import { positionMm, set, state, subscribe } from './state.js';

const html = String.raw;
const f = (v, digits = 2) => (v === undefined || v === null || !Number.isFinite(v) ? '–' : v.toFixed(digits));

export function renderPanel(element, actions) {
  element.innerHTML = html`
    <h2>Patient</h2>
    <select id="patient"></select> <span id="patient-figures"></span>
    <h2>Bar (scenario A)</h2>
    <label>Position along the sternum: <b id="position-text"></b></label>
    <input id="position" type="range" min="0.3" max="1" step="0.001" />
    <label>Position, mm from the notch <input id="position-mm" type="number" step="0.5" style="width:6em" /></label>
    <label>Force: <b id="force-text"></b></label>
    <input id="force" type="range" min="10" max="2000" step="1" />
    <label>Wanted lift, mm <input id="lift" type="number" step="0.5" style="width:6em" /> <button id="lift-apply">set force</button></label>
    <p style="color:#555">Keys: <kbd>↑</kbd>/<kbd>↓</kbd> bar 1 mm up/down the sternum, <kbd>←</kbd>/<kbd>→</kbd> force −/+ 5 N
      (with <kbd>Shift</kbd>: 10 mm, 50 N). Drag the bar in the view (or Shift-drag anywhere) to move it.</p>
    <h2>Live (from the response basis)</h2>
    <table id="live"></table>
    <h2>Against the average chest (the planner's C++)</h2>
    <table id="exact"></table>
    <label>Scenario B: <input id="compare" type="number" step="1" style="width:4em" /> mm nearer the notch</label>
    <h2>View</h2>
    <label><input type="checkbox" id="view-bone" /> ribcage (sternum, ribs, <span style="color:#3a7ca5">cartilage</span>)</label>
    <label><input type="checkbox" id="view-skin" /> skin, opacity <input id="opacity" type="range" min="0" max="1" step="0.05" style="width:8em" /></label>
    <label><input type="checkbox" id="view-average" /> average chest</label>
    <label><input type="checkbox" id="view-map" /> difference map on the predicted chest</label>
    <label><input type="checkbox" id="view-landmarks" /> landmarks</label>
    <label>colour map <select id="colormap">${colormapNames.map((n) => `<option>${n}</option>`).join('')}</select></label>
    <h2>Best placement</h2>
    <button id="search">search</button> <span id="search-best"></span>
    <div id="search-map"></div>
    <h2>Trainer</h2>
    <div id="trainer"></div>
    <h2>Plan</h2>
    <button id="export-json">plan JSON</button> <button id="export-png">PNG</button> <button id="export-ply">predicted chest PLY</button>
    <label>load a plan JSON <input id="load" type="file" accept=".json,application/json" /></label>`;
  const $ = (id) => element.querySelector(`#${id}`);
  $('patient').onchange = (e) => actions.loadPatient(e.target.value).then(() => actions.requestPlan(0));
  $('position').oninput = (e) => actions.setBar({ position: Number(e.target.value) });
  $('position-mm').onchange = (e) => actions.setBar({ position: Number(e.target.value) / state.info.sternal_length_mm });
  $('force').oninput = (e) => actions.setBar({ force: Number(e.target.value) });
  $('lift-apply').onclick = () => actions.setLift(Number($('lift').value));
  $('compare').onchange = (e) => {
    set({ compareMm: Number(e.target.value) });
    actions.requestPlan(0);
  };
  for (const key of ['bone', 'skin', 'average', 'map', 'landmarks']) $(`view-${key}`).onchange = (e) => set({ view: { [key]: e.target.checked } });
  $('opacity').oninput = (e) => set({ view: { opacity: Number(e.target.value) } });
  $('colormap').onchange = (e) => set({ view: { colormap: e.target.value } });
  $('search').onclick = actions.runSearch;
  $('export-json').onclick = actions.exportPlan;
  $('export-png').onclick = actions.exportPng;
  $('export-ply').onclick = actions.exportPly;
  $('load').onchange = async (e) => {
    try {
      await actions.loadPlan(await e.target.files[0].text());
    } catch (err) {
      set({ error: err.message });
    }
  };

  // While the bar is dragged the panel is redrawn ten times a second, not every frame: figures changing
  // faster cannot be read, and each redraw is a repaint of the panel (in a browser without a GPU, as
  // costly as drawing the chest). At rest, at once.
  let pending = 0;
  subscribe((s) => {
    if (s.dragging) {
      if (!pending) pending = setTimeout(() => ((pending = 0), draw(state)), 100);
      return;
    }
    clearTimeout(pending);
    pending = 0;
    draw(s);
  });
  function draw(s) {
    if ($('patient').options.length !== s.patients.length) {
      $('patient').innerHTML = s.patients.map((p) => `<option value="${p.id}">${p.id}</option>`).join('');
    }
    $('patient').value = s.patientId ?? '';
    const p = s.patients.find((q) => q.id === s.patientId);
    setText($('patient-figures'), p ? `Haller ${f(p.haller_index)}, depression ${f(p.depression_mm, 1)} mm` : '');
    const mm = positionMm(s);
    setText($('position-text'), `${f(s.bar.position, 3)} L = ${f(mm, 1)} mm`);
    if (document.activeElement !== $('position')) $('position').value = s.bar.position;
    if (document.activeElement !== $('position-mm')) $('position-mm').value = f(mm, 1);
    setText($('force-text'), `${f(s.bar.force, 0)} N`);
    if (document.activeElement !== $('force')) $('force').value = s.bar.force;
    if (document.activeElement !== $('compare')) $('compare').value = s.compareMm;
    for (const key of ['bone', 'skin', 'average', 'map', 'landmarks']) $(`view-${key}`).checked = s.view[key];
    $('opacity').value = s.view.opacity;
    $('colormap').value = s.view.colormap;
    const l = s.live;
    setHtml($('live'), l
      ? html`<tr><td>sternal lift</td><td id="live-lift">${f(l.liftMm)} mm</td></tr>
          <tr><td>force to lift by the depression (${f(s.info.depression_mm, 1)} mm)</td><td>${f(l.forceToLift, 0)} N</td></tr>
          <tr><td>linear range (lift ≤ ${f(s.info.linear_range_lift_mm, 0)} mm)</td><td id="live-range" class="${l.beyondLinear ? 'flag' : ''}">${l.beyondLinear ? 'beyond' : 'within'}</td></tr>
          <tr><td>update</td><td>${f(l.updateMs, 2)} ms</td></tr>`
      : '');
    const plan = s.plan;
    const current = plan && s.planFor && s.planFor.position === s.bar.position && s.planFor.force === s.bar.force;
    setHtml($('exact'), plan
      ? html`<tr><th></th>${plan.scenarios.map((c) => `<th>${c.name}</th>`).join('')}<th>before</th></tr>
          <tr><td>bar</td>${plan.scenarios.map((c) => `<td>${f(c.bar.position_in_mm ? c.bar.position : c.bar.position * s.info.sternal_length_mm, 1)} mm, ${f(c.bar.force_n, 0)} N</td>`).join('')}<td></td></tr>
          <tr><td>sternal lift, mm</td>${plan.scenarios.map((c, i) => `<td id="exact-lift-${i}">${f(c.sternum_lift_mm)}</td>`).join('')}<td></td></tr>
          <tr><td>RMS, mm</td>${plan.scenarios.map((c, i) => `<td id="exact-rms-${i}">${f(c.score.rms_mm)}</td>`).join('')}<td>${f(plan.before.rms_mm)}</td></tr>
          <tr><td>max |d|, mm</td>${plan.scenarios.map((c, i) => `<td id="exact-max-${i}">${f(c.score.max_abs_mm)}</td>`).join('')}<td>${f(plan.before.max_abs_mm)}</td></tr>
          <tr><td>central RMS, mm</td>${plan.scenarios.map((c, i) => `<td id="exact-central-${i}">${f(c.score.central.rms_mm)}</td>`).join('')}<td>${f(plan.before.central.rms_mm)}</td></tr>
          <tr><td>linear range</td>${plan.scenarios.map((c) => `<td class="${c.beyond_linear_range ? 'flag' : ''}">${c.beyond_linear_range ? 'beyond' : 'within'}</td>`).join('')}<td></td></tr>
          <tr><td colspan="4" style="text-align:left;color:#777">${current ? 'for the bar shown' : 'updating…'}</td></tr>`
      : '');
    drawSearch($('search-map'), $('search-best'), s, actions);
  }
}

// Views redraw on every change of the state (every frame while the bar moves): the document changes only
// where the text does, so that the browser lays out and paints no more than that.
function setText(element, text) {
  if (element.textContent !== text) element.textContent = text;
}
function setHtml(element, text) {
  if (element.pectusHtml === text) return;
  element.pectusHtml = text;
  element.innerHTML = text;
}

function drawSearch(element, best, s, actions) {
  const search = s.search;
  if (!search) {
    element.replaceChildren();
    best.textContent = '';
    return;
  }
  if (element.dataset.drawn === String(search.evaluations) + s.view.colormap) return;
  element.dataset.drawn = String(search.evaluations) + s.view.colormap;
  best.textContent = `best ${f(search.best.position, 3)} L, ${f(search.best.force_n, 0)} N: RMS ${f(search.best.objective_mm)} mm`;
  const P = search.positions.length, F = search.forces_n.length, cell = 18;
  const canvas = document.createElement('canvas');
  canvas.width = F * cell;
  canvas.height = P * cell;
  const g = canvas.getContext('2d');
  const values = search.objective_mm.flat().filter(Number.isFinite);
  const lo = Math.min(...values), hi = Math.max(...values);
  for (let i = 0; i < P; ++i) {
    for (let j = 0; j < F; ++j) {
      const [r, gr, b] = colour(s.view.colormap, 1 - (search.objective_mm[i][j] - lo) / Math.max(hi - lo, 1e-9));
      g.fillStyle = `rgb(${r * 255},${gr * 255},${b * 255})`;
      g.fillRect(j * cell, i * cell, cell - 1, cell - 1);
    }
  }
  canvas.title = 'RMS difference to the average chest: rows bar position (top: nearest the notch), columns force; click a cell to load it';
  canvas.onclick = (e) => {
    const r = canvas.getBoundingClientRect();
    const i = Math.floor(((e.clientY - r.top) / r.height) * P), j = Math.floor(((e.clientX - r.left) / r.width) * F);
    actions.setBar({ position: search.positions[i], force: search.forces_n[j] });
  };
  const caption = document.createElement('div');
  caption.textContent = `rows ${f(search.positions[0], 2)}–${f(search.positions[P - 1], 2)} L, columns ${f(search.forces_n[0], 0)}–${f(search.forces_n[F - 1], 0)} N; bright: lower RMS (${f(lo)}–${f(hi)} mm)`;
  element.replaceChildren(canvas, caption);
}
