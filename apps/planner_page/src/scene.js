// The 3D view, drawn from the state: the patient's ribcage (by material) and skin in the patient's frame
// placed by T_average_patient, the average chest and the predicted chest coloured by its difference in
// the average chest's frame, the landmarks and the bar. The deformation is applied every frame the bar
// changes, from the basis (basis.js).
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { colour } from './colormap.js';

const materialColours = [0xd9c9a3, 0xf2ead8, 0x7fb3d5]; // sternum, rib, costal cartilage

/// Whether WebGL draws in software here (SwiftShader, llvmpipe: no GPU, as in a headless browser or a
/// virtual machine): the view then trades multisampling and, while something moves, resolution for frame
/// rate.
function softwareWebGl() {
  try {
    const gl = document.createElement('canvas').getContext('webgl2') ?? document.createElement('canvas').getContext('webgl');
    const info = gl?.getExtension('WEBGL_debug_renderer_info');
    const name = info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : gl?.getParameter(gl.RENDERER) ?? '';
    gl?.getExtension('WEBGL_lose_context')?.loseContext();
    return /swiftshader|llvmpipe|softpipe|software/i.test(String(name));
  } catch {
    return false;
  }
}

/// A coarser triangulation of the same vertices, for frames while something moves (vertex clustering,
/// Rossignac and Borrel 1993): vertices are grouped in cubes of `cell` mm, each group stands at its first
/// vertex (which the deformation moves, as every vertex), and a triangle whose corners fall in fewer than
/// three groups is left out. Triangles [start, start + count) of `index`.
function clusteredIndex(position, index, start, count, cell) {
  const groups = new Map(), at = new Int32Array(position.length / 3).fill(-1), out = [];
  const groupOf = (v) => {
    if (at[v] < 0) {
      const key = `${Math.floor(position[3 * v] / cell)},${Math.floor(position[3 * v + 1] / cell)},${Math.floor(position[3 * v + 2] / cell)}`;
      if (!groups.has(key)) groups.set(key, v);
      at[v] = groups.get(key);
    }
    return at[v];
  };
  for (let f = start; f < start + count; ++f) {
    const a = groupOf(index[3 * f]), b = groupOf(index[3 * f + 1]), c = groupOf(index[3 * f + 2]);
    if (a !== b && b !== c && a !== c) out.push(a, b, c);
  }
  return out;
}

/// Gives `geometry` a coarse triangulation (clusteredIndex, cubes of twice its mean edge: about a fifth of
/// the triangles) beside its own, group by group; Scene.setMoving() swaps them.
function addCoarseDetail(geometry) {
  const p = geometry.attributes.position.array, index = geometry.index.array;
  let edges = 0;
  const faces = index.length / 3, step = Math.max(1, Math.floor(faces / 2000));
  let sampled = 0;
  for (let f = 0; f < faces; f += step, ++sampled) {
    const a = index[3 * f], b = index[3 * f + 1];
    edges += Math.hypot(p[3 * a] - p[3 * b], p[3 * a + 1] - p[3 * b + 1], p[3 * a + 2] - p[3 * b + 2]);
  }
  const cell = (2 * edges) / Math.max(sampled, 1);
  const ranges = geometry.groups.length ? geometry.groups : [{ start: 0, count: index.length, materialIndex: 0 }];
  const coarse = [], groups = [];
  for (const g of ranges) {
    const part = clusteredIndex(p, index, g.start / 3, g.count / 3, cell);
    groups.push({ start: coarse.length, count: part.length, materialIndex: g.materialIndex });
    coarse.push(...part);
  }
  geometry.userData.detail = {
    fine: { index: geometry.index, groups: geometry.groups.map((g) => ({ ...g })) },
    coarse: { index: new THREE.BufferAttribute(new Uint32Array(coarse), 1), groups: geometry.groups.length ? groups : [] },
  };
}

function setDetail(geometry, which) {
  const d = geometry?.userData.detail;
  if (!d) return;
  geometry.setIndex(d[which].index);
  geometry.clearGroups();
  for (const g of d[which].groups) geometry.addGroup(g.start, g.count, g.materialIndex);
}

export class Scene {
  constructor(element) {
    this.software = softwareWebGl();
    // The drawing buffer is not kept after a frame is shown (a copy of it per frame otherwise): the PNG
    // export draws and reads it in one go (main.js, exportPng).
    this.renderer = new THREE.WebGLRenderer({ antialias: !this.software });
    this.renderer.setPixelRatio(1);
    // While the bar or the camera moves: this fraction of the resolution (1 on a GPU); full again at rest.
    this.movingPixelRatio = this.software ? 0.35 : 1;
    this.renderer.setClearColor(0xf4f4f4);
    element.prepend(this.renderer.domElement);
    this.renderer.domElement.tabIndex = 0;
    this.element = element;
    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(35, 1, 1, 5000);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x666666, 2.2));
    const light = new THREE.DirectionalLight(0xffffff, 1.2);
    this.camera.add(light);
    this.scene.add(this.camera);
    this.patient = new THREE.Group();
    this.patient.matrixAutoUpdate = false;
    this.scene.add(this.patient);
    this.resize();
    new ResizeObserver(() => this.resize()).observe(element);
  }

  resize() {
    const w = Math.max(this.element.clientWidth, 1), h = Math.max(this.element.clientHeight, 1);
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
  }

  /// The patient's meshes (replacing any before).
  setPatient(info, bone, skin, landmarks) {
    this.patient.clear();
    const m = info.T_average_patient;
    this.patient.matrix.set(...m[0], ...m[1], ...m[2], ...m[3]);
    this.patient.matrixWorldNeedsUpdate = true;
    // Ribcage: faces grouped by material.
    const nb = info.bone.vertices, fb = info.bone.faces;
    const vertices = new Float32Array(bone, 0, 3 * nb);
    const faces = new Uint32Array(bone, 12 * nb, 3 * fb);
    const labels = new Uint32Array(bone, 12 * nb + 12 * fb, fb);
    const order = [...Array(fb).keys()].sort((a, b) => labels[a] - labels[b]);
    const index = new Uint32Array(3 * fb);
    order.forEach((f, i) => index.set(faces.subarray(3 * f, 3 * f + 3), 3 * i));
    const g = new THREE.BufferGeometry();
    this.boneRest = vertices.slice();
    g.setAttribute('position', new THREE.BufferAttribute(vertices.slice(), 3));
    g.setIndex(new THREE.BufferAttribute(index, 1));
    let start = 0;
    for (let label = 0; label < 3; ++label) {
      let count = 0;
      while (start + count < fb && labels[order[start + count]] === label) ++count;
      if (count) g.addGroup(3 * start, 3 * count, label);
      start += count;
    }
    g.computeVertexNormals();
    // The bone surface is closed and faces outwards: its back faces are never seen (half the drawing).
    this.bone = new THREE.Mesh(g, materialColours.map((c) => new THREE.MeshLambertMaterial({ color: c })));
    this.patient.add(this.bone);
    // Skin, translucent.
    const ns = info.skin.vertices, fs = info.skin.faces;
    this.skinRest = new Float32Array(skin, 0, 3 * ns).slice();
    const sg = new THREE.BufferGeometry();
    sg.setAttribute('position', new THREE.BufferAttribute(this.skinRest.slice(), 3));
    sg.setIndex(new THREE.BufferAttribute(new Uint32Array(skin, 24 * ns, 3 * fs), 1));
    sg.computeVertexNormals();
    addCoarseDetail(sg);
    // Both sides in one pass (three draws a translucent double-sided mesh twice otherwise, back faces
    // first): the skin is seen through once, and the second pass was the dearest part of a frame.
    this.skin = new THREE.Mesh(sg, new THREE.MeshLambertMaterial({ color: 0xe8b89a, transparent: true, opacity: 0.45, side: THREE.DoubleSide, depthWrite: false, forceSinglePass: true }));
    this.skin.renderOrder = 2;
    this.patient.add(this.skin);
    // Landmarks: the skin's (moving with it) and the bone's.
    const nl = info.landmarks.skin.length, nbl = info.landmarks.bone.length;
    this.landmarkRest = new Float32Array(landmarks, 0, 3 * nl).slice();
    this.landmarks = new THREE.Group();
    const sphere = new THREE.SphereGeometry(2.5, 12, 8);
    for (let i = 0; i < nl + nbl; ++i) {
      const dot = new THREE.Mesh(sphere, new THREE.MeshBasicMaterial({ color: i < nl ? 0xd62728 : 0x1f77b4 }));
      const p = new Float32Array(landmarks, 12 * i, 3);
      dot.position.set(p[0], p[1], p[2]);
      this.landmarks.add(dot);
    }
    this.patient.add(this.landmarks);
    // The bar: across the chest, behind the sternum at its level.
    const notch = info.landmarks.bone.indexOf('sternal_notch');
    const n = notch >= 0 ? new Float32Array(landmarks, 12 * (nl + notch), 3) : [0, 0, 0];
    this.notch = new THREE.Vector3(n[0], n[1], n[2]);
    this.bar = new THREE.Mesh(new THREE.CylinderGeometry(3, 3, 260, 16), new THREE.MeshLambertMaterial({ color: 0x555555 }));
    this.bar.rotation.z = Math.PI / 2;
    this.patient.add(this.bar);
    this.boneDisplacement = new Float32Array(3 * nb);
    this.skinDisplacement = new Float32Array(3 * ns);
    this.landmarkDisplacement = new Float32Array(3 * nl);
    this.frame(info);
  }

  /// The average chest mesh (average frame) and the predicted chest drawn over it.
  setAverage(average, mesh) {
    const nv = average.vertices, nf = average.faces;
    this.averageRest = new Float32Array(mesh, 0, 3 * nv).slice();
    const index = new THREE.BufferAttribute(new Uint32Array(mesh, 12 * nv, 3 * nf), 1);
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(this.averageRest.slice(), 3));
    g.setIndex(index);
    g.computeVertexNormals();
    this.average = new THREE.Mesh(g, new THREE.MeshLambertMaterial({ color: 0x9aa7b1, wireframe: true, transparent: true, opacity: 0.5 }));
    this.scene.add(this.average);
    const pg = new THREE.BufferGeometry();
    pg.setAttribute('position', new THREE.BufferAttribute(this.averageRest.slice(), 3));
    pg.setAttribute('color', new THREE.BufferAttribute(new Float32Array(3 * nv).fill(0.7), 3));
    pg.setIndex(index);
    pg.computeVertexNormals();
    addCoarseDetail(pg);
    this.predicted = new THREE.Mesh(pg, new THREE.MeshLambertMaterial({ vertexColors: true, side: THREE.DoubleSide }));
    this.predicted.visible = false;
    this.scene.add(this.predicted);
    this.anterior = average.anterior;
  }

  /// The camera in front of the chest (the average chest's anterior direction), the patient's head up
  /// (the patient's cranial axis, z, in the average chest's frame, made square to the view).
  frame(info) {
    const box = new THREE.Box3().setFromObject(this.patient);
    const centre = box.getCenter(new THREE.Vector3());
    const a = new THREE.Vector3(...(this.anterior ?? [0, -1, 0])).normalize();
    const up = new THREE.Vector3(0, 0, 1).transformDirection(this.patient.matrix);
    up.addScaledVector(a, -up.dot(a)).normalize();
    const size = box.getSize(new THREE.Vector3()).length();
    this.camera.position.copy(centre).addScaledVector(a, size * 1.6);
    this.camera.up.copy(up);
    this.controls.target.copy(centre);
    // OrbitControls turns about the up axis it read when it was made (three 0.187 keeps it in _quat): told
    // the new one.
    this.controls._quat.setFromUnitVectors(up, new THREE.Vector3(0, 1, 0));
    this.controls._quatInverse.copy(this.controls._quat).invert();
    this.controls.update();
  }

  /// The predicted chest of a plan's scenario: the average chest moved along its anterior direction by
  /// the difference (the relative skin model, as `pectus plan` draws it), coloured on ±limit mm.
  setPredicted(difference, limit, colormap) {
    if (!this.predicted) return;
    const p = this.predicted.geometry.attributes.position, c = this.predicted.geometry.attributes.color;
    const a = this.anterior, rgb = [0, 0, 0];
    for (let i = 0; i < difference.length; ++i) {
      const d = difference[i];
      const ok = d !== null && Number.isFinite(d);
      for (let k = 0; k < 3; ++k) p.array[3 * i + k] = this.averageRest[3 * i + k] + (ok ? d * a[k] : 0);
      if (ok) colour(colormap, 0.5 + d / (2 * limit), rgb);
      else rgb.fill(0.75);
      c.array.set(rgb, 3 * i);
    }
    p.needsUpdate = c.needsUpdate = true;
    this.predicted.geometry.computeVertexNormals();
  }

  /// Moves the ribcage (if `parts.bone`), skin (if `parts.skin`), landmarks and bar to the displacements
  /// (mm) of the bar at `mm` from the notch. `moving` (a drag under way) keeps the normals of the last
  /// frame at rest: the shading lags the shape by a drag, a tenth of a frame's work saved.
  applyDeformation(mm, parts = { bone: true, skin: true }, moving = false) {
    const move = (mesh, rest, d) => {
      const p = mesh.geometry.attributes.position;
      for (let i = 0; i < d.length; ++i) p.array[i] = rest[i] + d[i];
      p.needsUpdate = true;
      if (!moving) mesh.geometry.computeVertexNormals();
    };
    if (parts.bone) move(this.bone, this.boneRest, this.boneDisplacement);
    if (parts.skin) move(this.skin, this.skinRest, this.skinDisplacement);
    this.landmarks.children.forEach((dot, i) => {
      if (3 * i >= this.landmarkRest.length) return;
      dot.position.set(...[0, 1, 2].map((k) => this.landmarkRest[3 * i + k] + this.landmarkDisplacement[3 * i + k]));
    });
    this.bar.position.set(this.notch.x, this.notch.y + 8, this.notch.z - mm);
  }

  /// Visibility and opacity from the state's view.
  show(view) {
    if (!this.bone) return;
    this.bone.visible = view.bone;
    this.skin.visible = view.skin;
    this.skin.material.opacity = view.opacity;
    this.landmarks.visible = view.landmarks;
    if (this.average) this.average.visible = view.average;
    if (this.predicted) this.predicted.visible = view.map && this.predicted.userData.ready === true;
  }

  /// Something moves (true: dragging the bar or the camera) or came to rest (false): the resolution
  /// follows (movingPixelRatio). Returns whether it changed, so that the caller draws again.
  setMoving(moving) {
    const ratio = moving ? this.movingPixelRatio : 1;
    if (this.renderer.getPixelRatio() === ratio) return false;
    this.renderer.setPixelRatio(ratio);
    this.resize();
    // In software, the coarse triangulations too (addCoarseDetail).
    // (Not the ribcage: its ribs are a cell thick, and clustering tears them.)
    for (const mesh of [this.skin, this.predicted]) setDetail(mesh?.geometry, moving ? 'coarse' : 'fine');
    // The map's normals, if it was recoloured on the coarse triangles (the ribcage's and the skin's are
    // made at rest by the next deformation).
    if (!moving) this.predicted?.geometry.computeVertexNormals();
    return true;
  }

  render() {
    this.renderer.render(this.scene, this.camera);
  }
}
