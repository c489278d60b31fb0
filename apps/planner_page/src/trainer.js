// The Nuss trainer on the planner page (issue 16; docs/trainer.md, "The trainer in the planner page"). The
// server runs the session: the patient's trainer in the planner plugin, its haptic servo loop at 1 kHz
// reading a device the page moves. Here: the scene (pericardium, lungs, the planned tunnel, the
// introducer's tip and shaft, the force), a view square to the tunnel's plane with everything but a slab
// about it cut away, the pointer (drag), keys or a gamepad moving the device in that plane, the
// thoracoscope's view inset, the live score and the session's report.
import * as THREE from 'three';
import { getBinary, postJson, request } from './api.js';
import { set, state, subscribe } from './state.js';

// Okabe and Ito's colours, told apart with any colour vision.
const colours = { pericardium: 0xd55e00, lung: 0x56b4e9, tunnel: 0x009e73, tip: 0xf0e442, shaft: 0x333333, force: 0xcc79a7, device: 0x999999 };
const slabMm = 25; // drawn either side of the working plane in the main view
const html = String.raw;
const f = (v, digits = 1) => (v === undefined || v === null || !Number.isFinite(v) ? '–' : v.toFixed(digits));

export class Trainer {
  /// `scene`: the page's Scene (the patient's group, camera, renderer).
  constructor(scene) {
    this.scene = scene;
    this.group = null;
    this.inFlight = false;
    this.pointerDown = false;
    this.scopeCamera = new THREE.PerspectiveCamera(60, 4 / 3, 1, 2000);
    this.ray = new THREE.Raycaster();
    this.listen();
  }

  get active() {
    return Boolean(state.trainer.session) && !state.trainer.report && !this.finishing;
  }

  /// Starts a session for the patient shown: the server builds the scene (a second or two) and starts the
  /// servo loop; the view turns square to the tunnel's plane.
  async start(introducer = 'medium') {
    set({ trainer: { ...state.trainer, busy: 'building the trainer scene…', report: null, error: '' } });
    try {
      const info = await postJson('/api/trainer/start', { patient: state.patientId, introducer });
      const meshes = await getBinary(`/api/trainer/${info.session}/meshes`);
      this.build(info, meshes);
      this.barPhase = null;
      set({ trainer: { ...state.trainer, session: info.session, info, target: info.start_mm, tick: null, scope: null, score: null, report: null, bar: null, busy: '' } });
      this.saveView = { ...state.view };
      set({ view: { skin: false, average: false, map: false, landmarks: false } });
      document.getElementById('colorbar').hidden = true; // the planner's map is not shown
      this.send();
    } catch (e) {
      set({ trainer: { ...state.trainer, busy: '', error: e.message } });
    }
  }

  /// Ends the session: the server stops the loop, scores it, replays its record, and answers the report.
  async finish() {
    if (!state.trainer.session || this.finishing) return;
    // No device message after this one: the last in flight is answered first.
    this.finishing = true;
    this.wanted = false;
    while (this.inFlight) await new Promise((resolve) => setTimeout(resolve, 5));
    try {
      const report = await postJson('/api/trainer/finish', { session: state.trainer.session });
      set({ trainer: { ...state.trainer, report } });
    } catch (e) {
      set({ trainer: { ...state.trainer, error: e.message } });
    } finally {
      this.finishing = false;
    }
  }

  /// Leaves the trainer: the planner's view as it was.
  close() {
    if (this.active) this.finish();
    this.barPhase = null;
    if (this.group) this.scene.patient.remove(this.group);
    this.group = null;
    this.scene.renderer.clippingPlanes = [];
    if (this.saveView) set({ view: this.saveView });
    document.getElementById('colorbar').hidden = false;
    this.scene.bar.visible = true;
    this.scene.controls.enabled = true;
    this.scene.frame(state.info);
    set({ trainer: { ...state.trainer, session: null, info: null, tick: null, scope: null, score: null, report: null, bar: null } });
  }

  async recordText() {
    const r = state.trainer.report;
    if (!r) return '';
    return (await request(r.record)).text();
  }

  // ---- the scene --------------------------------------------------------------------------------------------
  build(info, meshes) {
    if (this.group) this.scene.patient.remove(this.group);
    const g = new THREE.Group();
    let at = 0;
    const mesh = (name, colour, opacity) => {
      const { vertices, faces } = info.meshes[name];
      const geometry = new THREE.BufferGeometry();
      geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(meshes, at, 3 * vertices), 3));
      at += 12 * vertices;
      geometry.setIndex(new THREE.BufferAttribute(new Uint32Array(meshes, at, 3 * faces), 1));
      at += 12 * faces;
      geometry.computeVertexNormals();
      // Both sides: the slab's cut opens the organs, and their inside is seen through the cut.
      const m = new THREE.Mesh(geometry, new THREE.MeshLambertMaterial({ color: colour, transparent: opacity < 1, opacity, depthWrite: opacity >= 1, side: THREE.DoubleSide }));
      g.add(m);
      return m;
    };
    this.pericardium = mesh('pericardium', colours.pericardium, 1);
    mesh('right_lung', colours.lung, 0.45);
    mesh('left_lung', colours.lung, 0.45);
    const t = info.tunnel;
    const line = new THREE.BufferGeometry().setFromPoints(t.points.map((p) => new THREE.Vector3(...p)));
    g.add(new THREE.Line(line, new THREE.LineDashedMaterial({ color: colours.tunnel, dashSize: 4, gapSize: 2 })).computeLineDistances());
    for (const p of [t.entry_port_mm, t.exit_port_mm]) {
      const ring = new THREE.Mesh(new THREE.TorusGeometry(6, 1, 8, 24), new THREE.MeshBasicMaterial({ color: colours.tunnel }));
      ring.position.set(...p);
      ring.rotation.y = Math.PI / 2;
      g.add(ring);
    }
    this.tip = new THREE.Mesh(new THREE.SphereGeometry(3, 16, 12), new THREE.MeshBasicMaterial({ color: colours.tip }));
    this.tip.add(new THREE.Mesh(new THREE.SphereGeometry(3.6, 16, 12), new THREE.MeshBasicMaterial({ color: 0x000000, side: THREE.BackSide })));
    this.shaft = new THREE.Mesh(new THREE.CylinderGeometry(1, 1, 1, 12), new THREE.MeshLambertMaterial({ color: colours.shaft }));
    this.device = new THREE.Mesh(new THREE.SphereGeometry(2, 12, 8), new THREE.MeshBasicMaterial({ color: colours.device, wireframe: true }));
    this.force = new THREE.ArrowHelper(new THREE.Vector3(1, 0, 0), new THREE.Vector3(), 1, colours.force, 6, 4);
    this.scopeMarker = new THREE.Mesh(new THREE.ConeGeometry(3, 10, 12), new THREE.MeshBasicMaterial({ color: colours.shaft }));
    g.add(this.tip, this.shaft, this.device, this.force, this.scopeMarker);
    this.scene.patient.add(g);
    this.group = g;
    this.scene.bar.visible = false;
    // The working plane: through the entry port, the tunnel's middle and the exit port, its normal towards
    // the head; the device moves in it (keys and the wheel move it off).
    const e = new THREE.Vector3(...t.entry_port_mm), x = new THREE.Vector3(...t.exit_port_mm);
    const m = new THREE.Vector3(...t.points[Math.floor(t.points.length / 2)]);
    const n = new THREE.Vector3().crossVectors(x.clone().sub(e), m.clone().sub(e)).normalize();
    if (n.z < 0) n.negate();
    this.plane = new THREE.Plane().setFromNormalAndCoplanarPoint(n, m);
    this.planeOffset = 0;
    this.centre = e.clone().add(x).multiplyScalar(0.5).lerp(m, 0.5);
    this.frameFromAbove();
  }

  /// The camera square to the working plane, from the head's side, the chest's front at the top.
  frameFromAbove() {
    const M = this.scene.patient.matrix;
    const centre = this.centre.clone().applyMatrix4(M);
    const n = this.plane.normal.clone().transformDirection(M);
    const anterior = new THREE.Vector3(0, -1, 0).transformDirection(M);
    anterior.addScaledVector(n, -anterior.dot(n)).normalize();
    const camera = this.scene.camera;
    camera.position.copy(centre).addScaledVector(n, 520);
    camera.up.copy(anterior);
    this.scene.controls.target.copy(centre);
    this.scene.controls._quat.setFromUnitVectors(anterior, new THREE.Vector3(0, 1, 0));
    this.scene.controls._quatInverse.copy(this.scene.controls._quat).invert();
    this.scene.controls.update();
    this.scene.controls.enabled = false;
    this.updateClipping();
  }

  updateClipping() {
    const M = this.scene.patient.matrix;
    const p = this.plane.clone();
    p.constant -= this.planeOffset;
    const above = p.clone().negate();
    above.constant += slabMm;
    const below = p.clone();
    below.constant += slabMm;
    this.clipping = [above.applyMatrix4(M), below.applyMatrix4(M)];
  }

  // ---- the device --------------------------------------------------------------------------------------------
  /// The patient-frame point of the working plane under a pointer at client (x, y), or null.
  pointOnPlane(clientX, clientY) {
    const canvas = this.scene.renderer.domElement;
    const r = canvas.getBoundingClientRect();
    this.ray.setFromCamera(new THREE.Vector2(((clientX - r.left) / r.width) * 2 - 1, -((clientY - r.top) / r.height) * 2 + 1), this.scene.camera);
    const p = this.plane.clone();
    p.constant -= this.planeOffset;
    const M = this.scene.patient.matrix;
    const hit = this.ray.ray.intersectPlane(p.applyMatrix4(M), new THREE.Vector3());
    return hit ? hit.applyMatrix4(M.clone().invert()) : null;
  }

  /// The client coordinates of a patient-frame point (tests drive the pointer with it).
  screenOf(point) {
    const canvas = this.scene.renderer.domElement;
    const r = canvas.getBoundingClientRect();
    const v = new THREE.Vector3(...point).applyMatrix4(this.scene.patient.matrix).project(this.scene.camera);
    return { x: r.left + ((v.x + 1) / 2) * r.width, y: r.top + ((1 - v.y) / 2) * r.height };
  }

  moveTarget(point) {
    set({ trainer: { ...state.trainer, target: point.toArray ? point.toArray() : point } });
    this.send();
  }

  /// Sends the device's target; one request at a time, the latest target when the last answer is in.
  send() {
    if (!this.active) return;
    if (this.inFlight) {
      this.wanted = true;
      return;
    }
    this.inFlight = true;
    this.wanted = false;
    const session = state.trainer.session;
    postJson('/api/trainer/device', { session, position: state.trainer.target, buttons: this.pointerDown ? 1 : 0 })
      .then((a) => session === state.trainer.session && !state.trainer.report && set({ trainer: { ...state.trainer, tick: a.tick ?? null, scope: a.scope ?? null, score: a.score ?? state.trainer.score } }))
      .catch((e) => set({ trainer: { ...state.trainer, error: e.message } }))
      .finally(() => {
        this.inFlight = false;
        if (this.wanted) this.send();
      });
  }

  listen() {
    const canvas = this.scene.renderer.domElement;
    canvas.addEventListener('pointerdown', (e) => {
      if (!this.active) return;
      e.stopImmediatePropagation();
      const p = this.pointOnPlane(e.clientX, e.clientY);
      if (!p) return;
      this.pointerDown = true;
      canvas.setPointerCapture(e.pointerId);
      this.moveTarget(p);
    }, { capture: true });
    canvas.addEventListener('pointermove', (e) => {
      if (!this.active || !this.pointerDown) return;
      e.stopImmediatePropagation();
      const p = this.pointOnPlane(e.clientX, e.clientY);
      if (p) this.moveTarget(p);
    }, { capture: true });
    canvas.addEventListener('pointerup', (e) => {
      if (!this.active) return;
      e.stopImmediatePropagation();
      this.pointerDown = false;
    }, { capture: true });
    canvas.addEventListener('wheel', (e) => {
      if (!this.active) return;
      e.preventDefault();
      this.offsetPlane(e.deltaY > 0 ? -1 : 1);
    }, { passive: false });
  }

  /// Moves the working plane (and the device with it) along its normal, mm.
  offsetPlane(mm) {
    this.planeOffset += mm;
    this.updateClipping();
    const t = new THREE.Vector3(...state.trainer.target).addScaledVector(this.plane.normal, mm);
    this.moveTarget(t);
  }

  /// The keys while a session runs: arrows move the device 1 mm in the plane (towards the chest's front,
  /// back, the patient's left and right as seen), Page Up/Down off it; Shift: 5 mm. True if it took the key.
  key(e) {
    if (!this.active) return false;
    const step = e.shiftKey ? 5 : 1;
    const cam = this.scene.camera, M = this.scene.patient.matrix.clone().invert();
    const upScreen = cam.up.clone().transformDirection(M);
    const right = new THREE.Vector3().crossVectors(upScreen, this.plane.normal).negate().normalize();
    const up = upScreen.addScaledVector(this.plane.normal, -upScreen.dot(this.plane.normal)).normalize();
    const moves = { ArrowUp: up, ArrowDown: up.clone().negate(), ArrowRight: right, ArrowLeft: right.clone().negate() };
    if (moves[e.key]) {
      this.moveTarget(new THREE.Vector3(...state.trainer.target).addScaledVector(moves[e.key], step));
      return true;
    }
    if (e.key === 'PageUp' || e.key === 'PageDown') {
      this.offsetPlane(e.key === 'PageUp' ? step : -step);
      return true;
    }
    return false;
  }

  /// Every frame: the gamepad (left stick in the plane, triggers off it), and the answers drawn.
  frame() {
    this.animateBar();
    if (!this.active) return;
    const pad = navigator.getGamepads?.().find((p) => p && p.connected);
    if (pad) {
      const [ax = 0, ay = 0] = pad.axes;
      const lt = pad.buttons[6]?.value ?? 0, rt = pad.buttons[7]?.value ?? 0;
      if (Math.hypot(ax, ay) > 0.15 || lt + rt > 0.1) {
        const s = this.screenOf(state.trainer.target);
        const p = this.pointOnPlane(s.x + 4 * ax, s.y + 4 * ay);
        if (p) this.moveTarget(p);
        if (lt + rt > 0.1) this.offsetPlane(0.5 * (rt - lt));
      }
    }
    if (!this.wanted && !this.inFlight && performance.now() - (this.polled ?? 0) > 100) {
      this.polled = performance.now();
      this.send(); // the score and the force go on while the hand rests
    }
  }

  /// The bar's passage once the tunnel is made: pulled through along it from the right port (2 s), then
  /// flipped about the line between the ports (1.5 s) while its force grows from 0 to the report's
  /// (F (1 - cos θ) / 2): the planner's basis deforms the ribcage every frame as it turns.
  passBar() {
    const r = state.trainer.report;
    if (!r?.bar?.score || !this.group || this.barPhase) return;
    const t = state.trainer.info.tunnel;
    const curve = new THREE.CatmullRomCurve3(t.points.map((p) => new THREE.Vector3(...p)));
    const geometry = new THREE.TubeGeometry(curve, 120, 3, 10, false);
    const entry = new THREE.Vector3(...t.entry_port_mm), exit = new THREE.Vector3(...t.exit_port_mm);
    this.barPivot = new THREE.Group();
    this.barPivot.position.copy(entry);
    const bar = new THREE.Mesh(geometry, new THREE.MeshLambertMaterial({ color: 0x777777 }));
    bar.position.copy(entry).negate();
    this.barPivot.add(bar);
    this.group.add(this.barPivot);
    this.barMesh = bar;
    this.barAxis = exit.clone().sub(entry).normalize();
    this.barPhase = { start: performance.now(), force: r.bar.force_n, position: r.bar.position };
    this.tip.visible = this.shaft.visible = this.force.visible = this.device.visible = false;
    set({ trainer: { ...state.trainer, bar: { phase: 'pulling', lift: 0 } } });
  }

  /// One frame of the bar's passage (the loop calls it); true while it moves.
  animateBar() {
    const b = this.barPhase;
    if (!b || b.done) return false;
    const seconds = (performance.now() - b.start) / 1000, pull = 2, flip = 1.5;
    const count = this.barMesh.geometry.index.count;
    if (seconds < pull) {
      // Whole rings of the tube, so that the bar's front is clean.
      const ring = 6 * 10;
      this.barMesh.geometry.setDrawRange(0, Math.floor(((seconds / pull) * count) / ring) * ring);
      return true;
    }
    this.barMesh.geometry.setDrawRange(0, count);
    const s = Math.min((seconds - pull) / flip, 1), angle = Math.PI * s;
    this.barPivot.quaternion.setFromAxisAngle(this.barAxis, angle);
    const force = (b.force * (1 - Math.cos(angle))) / 2;
    this.placeBar?.({ position: b.position, force: Math.max(force, 1) });
    const done = s >= 1;
    if (done) b.done = true;
    set({ trainer: { ...state.trainer, bar: { phase: done ? 'flipped' : 'flipping', angle_deg: (180 * angle) / Math.PI, force_n: force } } });
    return true;
  }

  /// Moves the introducer, the force and the scope to the latest tick.
  apply() {
    const t = state.trainer.tick;
    if (!this.group || !t) return;
    const tip = new THREE.Vector3(...t.proxy_mm), axis = new THREE.Vector3(...t.axis).normalize();
    this.tip.position.copy(tip);
    this.device.position.set(...t.device_mm);
    const length = 60;
    this.shaft.scale.set(1, length, 1);
    this.shaft.position.copy(tip).addScaledVector(axis, -length / 2);
    this.shaft.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), axis);
    const F = new THREE.Vector3(...t.force_n), magnitude = F.length();
    this.force.visible = magnitude > 0.01;
    if (this.force.visible) {
      this.force.position.copy(tip);
      this.force.setDirection(F.clone().normalize());
      this.force.setLength(8 + 12 * magnitude, 6, 4);
    }
    const s = state.trainer.scope;
    if (s) {
      const M = this.scene.patient.matrix;
      const eye = new THREE.Vector3(...s.eye_mm);
      this.scopeMarker.position.copy(eye);
      this.scopeMarker.quaternion.setFromUnitVectors(new THREE.Vector3(0, -1, 0), new THREE.Vector3(...s.forward));
      const c = this.scopeCamera;
      c.fov = s.vertical_fov_deg;
      c.aspect = s.aspect;
      c.position.copy(eye.applyMatrix4(M));
      c.up.copy(new THREE.Vector3(...s.up).transformDirection(M));
      c.lookAt(new THREE.Vector3(...s.eye_mm).add(new THREE.Vector3(...s.forward)).applyMatrix4(M));
      c.updateProjectionMatrix();
    }
  }

  /// The main view (cut to the slab) and the scope's view inset in the lower right corner.
  render() {
    const r = this.scene.renderer;
    if (!this.group) {
      r.render(this.scene.scene, this.scene.camera);
      return;
    }
    this.apply();
    r.clippingPlanes = this.clipping;
    r.render(this.scene.scene, this.scene.camera);
    r.clippingPlanes = [];
    if (!state.trainer.scope) return;
    const size = r.getSize(new THREE.Vector2());
    const w = Math.round(Math.min(320, size.x / 3)), h = Math.round(w / this.scopeCamera.aspect), m = 8;
    this.inset = { x: size.x - w - m, y: m, width: w, height: h };
    r.setScissorTest(true);
    r.setViewport(size.x - w - m, m, w, h);
    r.setScissor(size.x - w - m, m, w, h);
    const clear = r.getClearColor(new THREE.Color());
    r.setClearColor(0x1a0f0a);
    r.clear();
    this.scopeMarker.visible = false;
    r.render(this.scene.scene, this.scopeCamera);
    this.scopeMarker.visible = true;
    r.setClearColor(clear);
    r.setScissorTest(false);
    r.setViewport(0, 0, size.x, size.y);
  }
}

/// The trainer's part of the side panel.
export function renderTrainerPanel(element, trainer) {
  element.innerHTML = html`
    <label>Introducer <select id="trainer-introducer"><option value="small">small (6 mm)</option><option value="medium" selected>medium (8 mm)</option><option value="large">large (10 mm)</option></select></label>
    <button id="trainer-start">start a session</button> <button id="trainer-finish" disabled>finish</button> <button id="trainer-close" disabled>back to the planner</button>
    <p style="color:#555">Drag in the view to move the introducer's tip in the tunnel's plane (<kbd>←</kbd><kbd>→</kbd><kbd>↑</kbd><kbd>↓</kbd>
      1 mm, <kbd>Page Up</kbd>/<kbd>Page Down</kbd> or the wheel off the plane; <kbd>Shift</kbd>: 5 mm; a gamepad's left stick and triggers).
      Enter through the right <span id="trainer-entry"></span> space, pass under the sternum above the pericardium (<span style="color:#d55e00">■</span>), leave through the left one.
      The thoracoscope's view is in the lower right corner.</p>
    <table id="trainer-live" aria-live="polite"></table>
    <div id="trainer-report"></div>`;
  const $ = (id) => element.querySelector(`#${id}`);
  $('trainer-start').onclick = () => {
    element.scrollIntoView({ block: 'start' });
    trainer.start($('trainer-introducer').value);
  };
  $('trainer-finish').onclick = () => trainer.finish();
  $('trainer-close').onclick = () => trainer.close();
  subscribe((s) => {
    const t = s.trainer;
    $('trainer-start').disabled = !s.info || trainer.active || Boolean(t.busy);
    $('trainer-finish').disabled = !trainer.active;
    $('trainer-close').disabled = !t.session;
    $('trainer-entry').textContent = t.info ? t.info.tunnel.entry.name.replace('right ', '') + 'th' : '';
    const tick = t.tick, score = t.score;
    const live = tick ? html`<tr><td>time</td><td>${f(tick.time_s, 1)} s</td></tr>
      <tr><td>tip to the pericardium</td><td id="trainer-distance" class="${tick.pericardium_distance_mm < 5 ? 'flag' : ''}">${f(tick.pericardium_distance_mm)} mm</td></tr>
      <tr><td>force on the hand</td><td>${f(Math.hypot(...tick.force_n), 2)} N</td></tr>
      <tr><td>touching</td><td>${tick.organs.length ? tick.organs.join(', ') : 'nothing'}</td></tr>
      ${score ? html`<tr><td>score so far</td><td id="trainer-score">${f(score.score, 1)}</td></tr>
      <tr><td>nearest approach to the pericardium</td><td>${f(score.min_pericardium_distance_mm)} mm</td></tr>
      <tr><td>pericardial contacts</td><td class="${score.pericardial_contacts ? 'flag' : ''}">${score.pericardial_contacts}</td></tr>
      <tr><td>path, RMS off the planned tunnel</td><td>${f(score.path_length_mm, 0)} mm, ${f(score.rms_tunnel_deviation_mm)} mm</td></tr>` : ''}`
      : t.busy || t.error ? `<tr><td>${t.error ? 'error: ' + t.error : t.busy}</td></tr>` : '';
    if ($('trainer-live').pectusHtml !== live) $('trainer-live').innerHTML = $('trainer-live').pectusHtml = live;
    const barStatus = element.querySelector('#trainer-bar-status');
    if (barStatus) {
      const b = t.bar, live = s.live;
      const text = !b ? '' : b.phase === 'pulling' ? 'pulling the bar through the tunnel…'
        : `bar ${b.phase} (${f(b.angle_deg, 0)}°, ${f(b.force_n, 0)} N): sternal lift ${f(live?.liftMm, 1)} mm of its ${f(s.info?.depression_mm, 1)} mm depression`;
      if (barStatus.textContent !== text) barStatus.textContent = text;
    }
    const r = t.report;
    const report = r && r.score ? html`<h2>Session report</h2><table>
      <tr><td>score (100 minus the penalties)</td><td id="trainer-report-score">${f(r.score.score, 1)}</td></tr>
      <tr><td>nearest approach to the pericardium</td><td>${f(r.score.min_pericardium_distance_mm)} mm</td></tr>
      <tr><td>time within 5 mm of it</td><td>${f(r.score.time_near_pericardium_s, 2)} s</td></tr>
      <tr><td>pericardial contacts, peak force</td><td>${r.score.pericardial_contacts}, ${f(r.score.peak_pericardium_force_n, 2)} N</td></tr>
      <tr><td>peak force on the hand</td><td>${f(r.score.peak_force_n, 2)} N</td></tr>
      <tr><td>path length</td><td>${f(r.score.path_length_mm, 0)} mm</td></tr>
      <tr><td>RMS off the planned tunnel</td><td>${f(r.score.rms_tunnel_deviation_mm)} mm</td></tr>
      <tr><td>entry (planned)</td><td id="trainer-report-entry" class="${r.score.entry_as_planned ? '' : 'flag'}">${r.score.entry.name} (${r.score.planned_entry.name})</td></tr>
      <tr><td>exit (planned)</td><td id="trainer-report-exit" class="${r.score.exit_as_planned ? '' : 'flag'}">${r.score.exit.name} (${r.score.planned_exit.name})</td></tr>
      <tr><td>total time</td><td>${f(r.score.total_time_s, 1)} s</td></tr>
      <tr><td>servo loop: ticks, period p99</td><td>${r.loop.ticks}, ${f(r.loop.period_p99_ms, 3)} ms</td></tr>
      <tr><td>the record replays to the same scores</td><td id="trainer-report-replay">${r.replay_gives_the_same_scores ? 'yes' : 'no'}</td></tr>
      ${r.bar?.score ? html`<tr><th colspan="2" style="text-align:left">The bar through this tunnel (${f(r.bar.position_mm, 0)} mm from the notch, ${f(r.bar.force_n, 0)} N to lift the sternum by its depression)</th></tr>
      <tr><td>RMS against the average chest</td><td id="trainer-report-bar-rms">${f(r.bar.score.rms_mm, 2)} mm (before ${f(r.bar.before.rms_mm, 2)})</td></tr>
      <tr><td>central RMS</td><td>${f(r.bar.score.central.rms_mm, 2)} mm (before ${f(r.bar.before.central.rms_mm, 2)})</td></tr>` : ''}</table>
      <button id="trainer-record">download the record</button> ${r.bar?.score ? '<button id="trainer-pass-bar">pull the bar through and flip it</button> <button id="trainer-place-bar">place the bar there</button>' : ''}
      <p id="trainer-bar-status" aria-live="polite"></p>`
      : r ? `<p>${r.error}</p>` : '';
    if ($('trainer-report').pectusHtml !== report) {
      $('trainer-report').innerHTML = $('trainer-report').pectusHtml = report;
      if (r?.bar?.score) {
        // Back to the planner with the bar at the tunnel's level: the chest deforms as the bar is moved.
        $('trainer-pass-bar').onclick = () => trainer.passBar();
        $('trainer-place-bar').onclick = () => {
          trainer.close();
          trainer.placeBar?.({ position: r.bar.position, force: r.bar.force_n });
        };
      }
      if (r?.score) {
        $('trainer-record').onclick = async () => {
          const a = document.createElement('a');
          a.href = URL.createObjectURL(new Blob([await trainer.recordText()], { type: 'text/plain' }));
          a.download = `trainer_session_${r.session}_patient_${r.patient}.txt`;
          a.click();
          setTimeout(() => URL.revokeObjectURL(a.href), 1000);
        };
      }
    }
  });
}
