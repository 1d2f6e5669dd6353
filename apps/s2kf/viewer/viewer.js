// The s2kf viewer page's script (docs/viewer.md): decodes the motion data block, draws the tracked
// skeleton, the recorded and model markers (and the truth) with three.js, plays the motion, plots
// joint angles and the marker distance, and writes the scene state into #scene-state for tests.
// A live page (`s2kf live --view`, docs/live.md) gets its metadata and records by server-sent
// events instead and follows the newest frame.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/OrbitControls.js';

const MM = 0.001;  // data in mm, scene in metres
const DISTANCE_SCALE_MM = 50;  // marker colours run from 0 (green) to 50 mm and more (red)
const COLOURS = { joint: 0xf2f2f2, bone: 0xd8d8d8, model: 0x4a90d9, hidden: 0x9a9a9a, truth: 0xb36bff };

function fail(message) {
  const box = document.getElementById('error');
  box.textContent = message;
  box.hidden = false;
  document.getElementById('viewer').hidden = true;
  const state = document.getElementById('scene-state');
  state.textContent = JSON.stringify({ ok: false, error: message, errors: window.s2kfErrors });
  document.title = 's2kf viewer: error';
}

// FNV-1a over the bytes: the writer stores it so a damaged block is named as such.
function fnv1a(bytes) {
  let hash = 0x811c9dc5;
  for (let i = 0; i < bytes.length; ++i) {
    hash ^= bytes[i];
    hash = Math.imul(hash, 0x01000193) >>> 0;
  }
  return hash >>> 0;
}

// The metadata and the float32 frame records, checked; throws an Error whose message is for the user.
function loadData() {
  const metaElement = document.getElementById('s2kf-meta');
  const dataElement = document.getElementById('s2kf-data');
  if (!metaElement) throw new Error('This page has no metadata block (#s2kf-meta): it was not written by s2kf or was cut.');
  if (!dataElement) throw new Error('This page has no motion data block (#s2kf-data): it was not written by s2kf or was cut.');
  let meta;
  try {
    meta = JSON.parse(metaElement.textContent);
  } catch (e) {
    throw new Error('The metadata block (#s2kf-meta) is corrupt: ' + e.message);
  }
  if (meta.format !== 's2kf-viewer-1') throw new Error('The metadata block names format "' + meta.format + '", this page reads s2kf-viewer-1.');
  let binary;
  try {
    binary = atob(dataElement.textContent.replace(/\s+/g, ''));
  } catch (e) {
    throw new Error('The motion data block (#s2kf-data) is corrupt: it is not valid base64.');
  }
  const expected = meta.frames_stored * meta.floats_per_frame * 4;
  if (binary.length !== expected)
    throw new Error('The motion data block (#s2kf-data) is corrupt: ' + binary.length + ' bytes, the metadata promises ' +
                    expected + ' (' + meta.frames_stored + ' frames of ' + meta.floats_per_frame * 4 + ' bytes).');
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; ++i) bytes[i] = binary.charCodeAt(i);
  if (fnv1a(bytes) !== meta.checksum_fnv1a)
    throw new Error('The motion data block (#s2kf-data) is corrupt: its checksum does not match the metadata.');
  // Little-endian float32 records, read explicitly so a big-endian browser reads them right too.
  const view = new DataView(bytes.buffer);
  const values = new Float32Array(bytes.length / 4);
  for (let i = 0; i < values.length; ++i) values[i] = view.getFloat32(4 * i, true);
  const block = {};
  for (const b of meta.blocks) block[b.name] = b;
  return { meta, values, block };
}

function distanceColour(mm, colour) {
  // Green (0 mm) through yellow to red (DISTANCE_SCALE_MM and beyond).
  const t = Math.min(Math.max(mm / DISTANCE_SCALE_MM, 0), 1);
  return colour.setHSL((1 - t) * 120 / 360, 0.85, 0.5);
}

function parseFragment() {
  const options = {};
  for (const part of location.hash.replace(/^#/, '').split('&')) {
    if (!part) continue;
    const [key, value] = part.split('=');
    options[decodeURIComponent(key)] = value === undefined ? '' : decodeURIComponent(value);
  }
  return options;
}

// One record sent by s2kf live: base64 of little-endian float32 values.
function decodeRecord(text, floats) {
  const binary = atob(text);
  if (binary.length !== 4 * floats)
    throw new Error('A live record has ' + binary.length + ' bytes, the metadata promises ' + 4 * floats + '.');
  const view = new DataView(new ArrayBuffer(binary.length));
  for (let i = 0; i < binary.length; ++i) view.setUint8(i, binary.charCodeAt(i));
  const values = new Float32Array(floats);
  for (let i = 0; i < floats; ++i) values[i] = view.getFloat32(4 * i, true);
  return values;
}

// The live page: the metadata comes as the event "meta", each tracked frame as the event "frame",
// the stream's end as "end". The scene starts with the first frame.
function startLive() {
  const fragment = parseFragment();
  const source = new EventSource('events');
  let meta = null, viewer = null, received = 0;
  const status = (text) => {
    const notice = document.getElementById('notice');
    notice.hidden = false;
    notice.textContent = text;
  };
  status('Waiting for s2kf live to send the first frame...');
  source.addEventListener('meta', (e) => { meta = JSON.parse(e.data); });
  source.addEventListener('frame', (e) => {
    try {
      if (!meta) throw new Error('A live frame arrived before the metadata.');
      const record = decodeRecord(e.data, meta.floats_per_frame);
      ++received;
      if (!viewer) {
        const block = {};
        for (const b of meta.blocks) block[b.name] = b;
        viewer = main({ meta, values: record, block }, { source, fragment });
        status('Live from ' + meta.name + ' at ' + meta.rate + ' Hz.');
      } else {
        viewer.push(record, received);
      }
    } catch (error) {
      source.close();
      fail('The live view failed: ' + error.message);
    }
  });
  source.addEventListener('end', (e) => {
    source.close();
    status('The stream has ended (' + e.data + ').');
  });
  source.addEventListener('open', () => {
    if (meta) status('Live from ' + meta.name + ' at ' + meta.rate + ' Hz.');
  });
  source.addEventListener('error', () => {
    if (source.readyState !== EventSource.CLOSED) status('The connection to s2kf live was lost; trying again...');
  });
}

// Draws the records of `data`; `live` (the event source and the URL fragment) makes the page
// follow the stream: returns { push(record) }, which appends a frame and shows it.
function main(data, live) {
  const { meta, block } = data;
  let values = data.values;
  const F = meta.floats_per_frame;
  let N = live ? 1 : meta.frames_stored;
  // A live page keeps the last few seconds for its plots.
  const windowFrames = live ? Math.max(1, meta.live_window_frames || 1000) : N;
  const P = meta.skeleton.points.length, M = meta.markers.length;
  const hasTruth = Boolean(block.truth_skeleton);
  const at = (frame, name, k) => values[frame * F + block[name].offset + k];
  const frameNumber = (i) => at(i, 'frame', 0);
  const storedIndexOf = (recordingFrame) => {
    // The stored frame nearest to a recording frame number (frames may be decimated).
    let best = 0;
    for (let i = 0; i < N; ++i)
      if (Math.abs(frameNumber(i) - recordingFrame) < Math.abs(frameNumber(best) - recordingFrame)) best = i;
    return best;
  };

  // ---- scene ----
  const holder = document.getElementById('canvas-holder');
  const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setSize(Math.max(holder.clientWidth, 100), Math.max(holder.clientHeight, 100));
  holder.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0x1d1f24);
  const camera = new THREE.PerspectiveCamera(40, renderer.domElement.width / renderer.domElement.height, 0.05, 200);
  camera.up.set(0, 0, 1);  // the lab's z is up
  scene.add(new THREE.AmbientLight(0xffffff, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 1.8);
  sun.position.set(2, -3, 5);
  scene.add(sun);

  // Extent of the motion: the camera frames it, the grid covers it.
  const lo = new THREE.Vector3(Infinity, Infinity, Infinity), hi = new THREE.Vector3(-Infinity, -Infinity, -Infinity);
  for (let i = 0; i < N; ++i)
    for (let p = 0; p < P; ++p) {
      const v = new THREE.Vector3(at(i, 'skeleton', 3 * p), at(i, 'skeleton', 3 * p + 1), at(i, 'skeleton', 3 * p + 2)).multiplyScalar(MM);
      if (Number.isFinite(v.x)) { lo.min(v); hi.max(v); }
    }
  if (!Number.isFinite(lo.x)) { lo.set(-1, -1, 0); hi.set(1, 1, 1.8); }
  const centre = lo.clone().add(hi).multiplyScalar(0.5);
  const size = Math.max(hi.x - lo.x, hi.y - lo.y, hi.z - lo.z, 1.8);
  const gridSize = Math.ceil((Math.max(hi.x - lo.x, hi.y - lo.y) + 2) / 1) * 1;
  const grid = new THREE.GridHelper(gridSize, gridSize * 2, 0x555555, 0x333333);
  grid.rotation.x = Math.PI / 2;  // GridHelper lies in x-z; the lab floor is x-y
  grid.position.set(Math.round(centre.x), Math.round(centre.y), 0);
  scene.add(grid);
  scene.add(new THREE.AxesHelper(0.5));

  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(centre);
  camera.position.copy(centre).add(new THREE.Vector3(0.55, 2.0, 0.35).multiplyScalar(size * 1.0));
  controls.update();

  const sphere = (radius) => new THREE.SphereGeometry(radius, 16, 12);
  const instanced = (geometry, material, count) => {
    const mesh = new THREE.InstancedMesh(geometry, material, Math.max(count, 1));
    mesh.instanceMatrix.setUsage(THREE.DynamicDrawUsage);
    mesh.frustumCulled = false;
    scene.add(mesh);
    return mesh;
  };
  // Flat colours: a test reads them back from the canvas.
  const jointMesh = instanced(sphere(0.022), new THREE.MeshBasicMaterial({ color: COLOURS.joint }), P);
  const recordedMesh = instanced(sphere(0.014), new THREE.MeshLambertMaterial({ color: 0xffffff }), M);
  const modelMesh = instanced(sphere(0.010), new THREE.MeshLambertMaterial({ color: COLOURS.model }), M);
  // Hidden markers: a wire sphere at the model's position (looks the same from every side).
  const hiddenMesh = instanced(new THREE.SphereGeometry(0.016, 8, 6),
                               new THREE.MeshBasicMaterial({ color: COLOURS.hidden, wireframe: true }), M);
  // Every instance gets a colour now, so the shader is built with instance colours from the start.
  for (let m = 0; m < M; ++m) recordedMesh.setColorAt(m, new THREE.Color(0xffffff));
  const truthMesh = hasTruth ? instanced(sphere(0.016), new THREE.MeshBasicMaterial({ color: COLOURS.truth, transparent: true, opacity: 0.45 }), P) : null;
  const lineSet = (pairs, material) => {
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(pairs * 6), 3));
    const lines = new THREE.LineSegments(geometry, material);
    lines.frustumCulled = false;
    scene.add(lines);
    return lines;
  };
  const bones = meta.skeleton.bones;
  const boneLines = lineSet(bones.length, new THREE.LineBasicMaterial({ color: COLOURS.bone }));
  const residualLines = lineSet(M, new THREE.LineBasicMaterial({ color: 0xffffff, vertexColors: true }));
  residualLines.geometry.setAttribute('color', new THREE.BufferAttribute(new Float32Array(M * 6), 3));
  const truthLines = hasTruth ? lineSet(bones.length, new THREE.LineBasicMaterial({ color: COLOURS.truth, transparent: true, opacity: 0.5 })) : null;
  if (hasTruth) document.getElementById('legend-truth').hidden = false;
  else document.getElementById('layer-truth').parentElement.hidden = true;

  const matrix = new THREE.Matrix4(), hiddenScale = new THREE.Matrix4().makeScale(0, 0, 0), colour = new THREE.Color();
  const point = (i, name, k) => new THREE.Vector3(at(i, name, 3 * k), at(i, name, 3 * k + 1), at(i, name, 3 * k + 2)).multiplyScalar(MM);
  const place = (mesh, k, v) => mesh.setMatrixAt(k, Number.isFinite(v.x) ? matrix.makeTranslation(v.x, v.y, v.z) : hiddenScale);
  const setLine = (lines, k, a, b) => {
    const position = lines.geometry.attributes.position;
    const ok = Number.isFinite(a.x) && Number.isFinite(b.x);
    position.setXYZ(2 * k, ok ? a.x : 0, ok ? a.y : 0, ok ? a.z : 0);
    position.setXYZ(2 * k + 1, ok ? b.x : 0, ok ? b.y : 0, ok ? b.z : 0);
  };

  const layers = {
    recorded: document.getElementById('layer-recorded'),
    model: document.getElementById('layer-model'),
    truth: document.getElementById('layer-truth'),
  };
  const fragment = parseFragment();
  if (fragment.layers !== undefined) {
    const wanted = fragment.layers.split(',');
    for (const name of Object.keys(layers)) layers[name].checked = wanted.includes(name);
  }

  let current = 0;
  let markerDistances = new Array(M).fill(NaN);
  function showFrame(i) {
    current = Math.min(Math.max(i, 0), N - 1);
    const joints = [];
    for (let p = 0; p < P; ++p) { joints.push(point(current, 'skeleton', p)); place(jointMesh, p, joints[p]); }
    bones.forEach(([a, b], k) => setLine(boneLines, k, joints[a], joints[b]));
    const residualColour = residualLines.geometry.attributes.color;
    let hidden = 0;
    for (let m = 0; m < M; ++m) {
      const model = point(current, 'model_markers', m), recorded = point(current, 'recorded_markers', m);
      const seen = Number.isFinite(recorded.x);
      hidden += seen ? 0 : 1;
      markerDistances[m] = seen && Number.isFinite(model.x) ? model.distanceTo(recorded) / MM : NaN;
      place(recordedMesh, m, recorded);
      place(modelMesh, m, seen ? model : new THREE.Vector3(NaN, 0, 0));
      place(hiddenMesh, m, seen ? new THREE.Vector3(NaN, 0, 0) : model);
      if (seen) {
        distanceColour(Number.isFinite(markerDistances[m]) ? markerDistances[m] : DISTANCE_SCALE_MM, colour);
        recordedMesh.setColorAt(m, colour);
        residualColour.setXYZ(2 * m, colour.r, colour.g, colour.b);
        residualColour.setXYZ(2 * m + 1, colour.r, colour.g, colour.b);
      }
      setLine(residualLines, m, seen ? recorded : new THREE.Vector3(NaN, 0, 0), model);
    }
    if (hasTruth) {
      const truth = [];
      for (let p = 0; p < P; ++p) { truth.push(point(current, 'truth_skeleton', p)); place(truthMesh, p, truth[p]); }
      bones.forEach(([a, b], k) => setLine(truthLines, k, truth[a], truth[b]));
      truthMesh.instanceMatrix.needsUpdate = true;
      truthLines.geometry.attributes.position.needsUpdate = true;
    }
    for (const mesh of [jointMesh, recordedMesh, modelMesh, hiddenMesh]) mesh.instanceMatrix.needsUpdate = true;
    if (recordedMesh.instanceColor) recordedMesh.instanceColor.needsUpdate = true;
    boneLines.geometry.attributes.position.needsUpdate = true;
    residualLines.geometry.attributes.position.needsUpdate = true;
    residualColour.needsUpdate = true;
    recordedMesh.visible = residualLines.visible = layers.recorded.checked;
    modelMesh.visible = hiddenMesh.visible = layers.model.checked;
    if (hasTruth) truthMesh.visible = truthLines.visible = layers.truth.checked;

    timeline.value = String(current);
    const tracked = Number.isFinite(at(current, 'pose', 0));
    frameLabel.textContent = 'frame ' + frameNumber(current) + (live ? '' : ' of ' + meta.frames_in_motion) + ', ' +
      at(current, 'time', 0).toFixed(3) + ' s' + (tracked ? '' : ' (not tracked)') + ', ' + hidden + ' hidden';
    const meanDistance = at(current, 'mean_marker_distance', 0);
    distanceValue.textContent = Number.isFinite(meanDistance) ? meanDistance.toFixed(1) + ' mm' : 'n/a';
    drawPlots();
    render();
  }

  // ---- plots ----
  const timeline = document.getElementById('timeline');
  const frameLabel = document.getElementById('frame-label');
  const distanceValue = document.getElementById('distance-value');
  const jointSelect = document.getElementById('joint-select');
  meta.joints.forEach((joint, j) => jointSelect.add(new Option(joint.name, String(j))));
  jointSelect.value = String(Math.max(0, meta.joints.findIndex((joint) => joint.name === (fragment.joint || 'LKx'))));
  timeline.max = String(N - 1);

  function plot(canvas, series, lines, unit) {
    const g = canvas.getContext('2d');
    const W = canvas.width, H = canvas.height, left = 40, right = 6, top = 6, bottom = 16;
    g.clearRect(0, 0, W, H);
    let min = Infinity, max = -Infinity;
    for (const v of series) if (Number.isFinite(v)) { min = Math.min(min, v); max = Math.max(max, v); }
    for (const l of lines) { min = Math.min(min, l.value); max = Math.max(max, l.value); }
    if (!Number.isFinite(min)) { min = 0; max = 1; }
    if (max - min < 1e-9) { max += 1; min -= 1; }
    const pad = 0.05 * (max - min); min -= pad; max += pad;
    const x = (i) => left + (W - left - right) * (N > 1 ? i / (N - 1) : 0);
    const y = (v) => top + (H - top - bottom) * (1 - (v - min) / (max - min));
    g.strokeStyle = '#444'; g.fillStyle = '#9aa'; g.font = '10px sans-serif';
    g.strokeRect(left, top, W - left - right, H - top - bottom);
    g.fillText(max.toFixed(0) + unit, 2, top + 8);
    g.fillText(min.toFixed(0) + unit, 2, H - bottom);
    g.fillText(String(frameNumber(0)), left, H - 3);
    g.fillText(String(frameNumber(N - 1)), W - right - 30, H - 3);
    for (const l of lines) {
      g.strokeStyle = l.colour; g.setLineDash([4, 3]); g.beginPath();
      g.moveTo(left, y(l.value)); g.lineTo(W - right, y(l.value)); g.stroke();
      g.setLineDash([]); g.fillStyle = l.colour; g.fillText(l.label, W - right - 60, y(l.value) - 2);
    }
    g.strokeStyle = '#7fc8ff'; g.beginPath();
    let drawing = false;
    series.forEach((v, i) => {
      if (!Number.isFinite(v)) { drawing = false; return; }
      if (drawing) g.lineTo(x(i), y(v)); else g.moveTo(x(i), y(v));
      drawing = true;
    });
    g.stroke();
    g.strokeStyle = '#ffcc33'; g.beginPath(); g.moveTo(x(current), top); g.lineTo(x(current), H - bottom); g.stroke();
  }
  const degrees = 180 / Math.PI;
  let distanceSeries = Array.from({ length: N }, (_, i) => at(i, 'mean_marker_distance', 0));
  function drawPlots() {
    const j = Number(jointSelect.value);
    const joint = meta.joints[j];
    const angles = Array.from({ length: N }, (_, i) => at(i, 'pose', 6 + j) * degrees);
    plot(document.getElementById('angle-plot'), angles,
         [{ value: joint.lower * degrees, label: 'lower limit', colour: '#e06060' },
          { value: joint.upper * degrees, label: 'upper limit', colour: '#e06060' }], '\u00b0');
    const angle = angles[current];
    document.getElementById('joint-value').textContent = Number.isFinite(angle) ? angle.toFixed(1) + '\u00b0' : 'n/a';
    plot(document.getElementById('distance-plot'), distanceSeries, [], '');
  }

  // ---- summary ----
  document.getElementById('title').textContent = live ? meta.name + ' (live, ' + meta.rate + ' Hz)'
    : meta.name + ' (' + meta.frames_in_motion + ' frames, ' + meta.rate + ' Hz)';
  if (meta.decimated) {
    const notice = document.getElementById('notice');
    notice.hidden = false;
    notice.textContent = 'Long recording: 1 frame in ' + meta.stride + ' is shown (' + N + ' of ' + meta.frames_in_motion +
      ' frames), to keep the page under ' + (meta.data_limit_bytes / 1048576).toFixed(0) + ' MiB of motion data.';
  }
  const s = meta.summary || {};
  if (live) document.getElementById('summary').hidden = true;
  const rows = [];
  const mm = (v) => (typeof v === 'number' ? v.toFixed(1) + ' mm' : 'n/a');
  const text = (v) => document.createTextNode(String(v));
  rows.push(['input', s.input], ['method', s.method + (s.smoothed ? ' (smoothed)' : '')],
            ['marker set', s.marker_set + ' (' + s.marker_set_source + ')'],
            ['markers used', (s.markers_used || []).length + ' (' + (s.labels_ignored || []).length + ' labels ignored)'],
            ['height', mm(s.height_mm) + ' (' + s.height_source + ')'],
            ['calibration', s.calibration ? s.calibration.frames + ' frames, ' + mm(s.calibration.mean_marker_distance_before_mm) +
              ' -> ' + mm(s.calibration.mean_marker_distance_after_mm) : 'none'],
            ['tracked', s.frames_tracked + ' of ' + s.frames + ' frames'],
            ['marker distance', mm(s.mean_marker_distance_mm) + ' after convergence (frame ' + s.converged_frame + '), ' +
              mm(s.mean_marker_distance_all_frames_mm) + ' over all']);
  if (s.truth) rows.push(['truth', 'all-joint RMS ' + Number(s.truth.all_joint_rms_deg).toFixed(2) + '\u00b0, root ' +
                          mm(s.truth.root_position_rms_mm) + ', worst joint ' + s.truth.worst_joint]);
  const table = document.createElement('table');
  for (const [key, value] of rows) {
    const tr = table.insertRow();
    tr.insertCell().appendChild(text(key));
    tr.insertCell().appendChild(text(value));
  }
  const warnings = table.insertRow();
  warnings.insertCell().appendChild(text('warnings'));
  const list = document.createElement('ul');
  for (const w of s.warnings || []) list.appendChild(document.createElement('li')).appendChild(text(w));
  if (!(s.warnings || []).length) list.appendChild(document.createElement('li')).appendChild(text('none'));
  warnings.insertCell().appendChild(list);
  document.getElementById('summary').appendChild(table);
  const ticks = document.getElementById('legend-ticks');
  for (let d = 0; d <= DISTANCE_SCALE_MM; d += 10) ticks.appendChild(document.createElement('span')).textContent = d === DISTANCE_SCALE_MM ? '\u2265' + d : String(d);
  const stops = [];
  for (let d = 0; d <= DISTANCE_SCALE_MM; d += 5) stops.push('#' + distanceColour(d, colour).getHexString());
  document.getElementById('legend-bar').style.background = 'linear-gradient(to right, ' + stops.join(', ') + ')';

  // ---- rendering and the scene state ----
  function render() {
    controls.update();
    renderer.render(scene, camera);
  }
  function sceneState() {
    // Joint centres as the page holds them (mm), their pixels (CSS pixels, origin top left) and the
    // colour the canvas shows there, read back from the drawing buffer.
    const gl = renderer.getContext();
    const ratio = renderer.getPixelRatio();
    const width = renderer.domElement.clientWidth, height = renderer.domElement.clientHeight;
    const pixel = new Uint8Array(4);
    const joints = [];
    for (let p = 0; p < P; ++p) {
      const v = point(current, 'skeleton', p);
      const entry = { name: meta.skeleton.points[p], mm: [v.x / MM, v.y / MM, v.z / MM] };
      if (Number.isFinite(v.x)) {
        const ndc = v.clone().project(camera);
        const px = [(ndc.x + 1) / 2 * width, (1 - ndc.y) / 2 * height];
        entry.pixel = px;
        gl.readPixels(Math.floor(px[0] * ratio), Math.floor((height - px[1]) * ratio), 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
        entry.rgb = [pixel[0], pixel[1], pixel[2]];
      }
      joints.push(entry);
    }
    camera.updateMatrixWorld();
    const viewProjection = new THREE.Matrix4().multiplyMatrices(camera.projectionMatrix, camera.matrixWorldInverse);
    return {
      ok: true, frame: frameNumber(current), stored_index: current, time: at(current, 'time', 0),
      canvas: [width, height], joint_colour: '#' + new THREE.Color(COLOURS.joint).getHexString(),
      // Column-major 4x4, acting on metres.
      view_projection: viewProjection.elements, joints,
      marker_distances_mm: markerDistances.map((d) => (Number.isFinite(d) ? d : null)),
      frames_stored: N, decimated: Boolean(meta.decimated), errors: window.s2kfErrors,
    };
  }
  function writeState(extra) {
    const state = sceneState();
    Object.assign(state, extra || {});
    document.getElementById('scene-state').textContent = JSON.stringify(state);
    document.title = meta.name + ' \u2014 frame ' + state.frame;
  }

  // ---- playback ----
  let playing = false, speed = 1, playStart = 0, playFrom = 0;
  const playButton = document.getElementById('play');
  function tick(now) {
    if (!playing) return;
    const elapsed = (now - playStart) / 1000 * speed;  // seconds of recording
    const startTime = at(playFrom, 'time', 0);
    let i = playFrom;
    while (i + 1 < N && at(i + 1, 'time', 0) - startTime <= elapsed) ++i;
    if (i + 1 >= N && at(N - 1, 'time', 0) - startTime <= elapsed) { playFrom = 0; playStart = now; i = 0; }
    if (i !== current) showFrame(i);
    requestAnimationFrame(tick);
  }
  function setPlaying(on) {
    playing = on;
    playButton.textContent = on ? 'pause' : 'play';
    if (on) { playFrom = current; playStart = performance.now(); requestAnimationFrame(tick); }
  }
  playButton.addEventListener('click', () => setPlaying(!playing));
  document.getElementById('speed').addEventListener('change', (e) => {
    speed = Number(e.target.value);
    if (playing) setPlaying(true);
  });
  timeline.addEventListener('input', () => { showFrame(Number(timeline.value)); if (playing) setPlaying(true); writeState(); });
  jointSelect.addEventListener('change', drawPlots);
  for (const box of Object.values(layers)) box.addEventListener('change', () => showFrame(current));
  controls.addEventListener('change', () => renderer.render(scene, camera));
  window.addEventListener('keydown', (e) => {
    if (e.key === ' ') { setPlaying(!playing); e.preventDefault(); }
    if (e.key === 'ArrowRight') showFrame(current + 1);
    if (e.key === 'ArrowLeft') showFrame(current - 1);
  });
  window.addEventListener('resize', () => {
    renderer.setSize(Math.max(holder.clientWidth, 100), Math.max(holder.clientHeight, 100));
    camera.aspect = renderer.domElement.width / renderer.domElement.height;
    camera.updateProjectionMatrix();
    render();
  });
  window.addEventListener('hashchange', () => {
    const f = parseFragment();
    if (f.frame !== undefined) { showFrame(storedIndexOf(Number(f.frame))); writeState(); }
  });

  if (live) return followStream();
  showFrame(fragment.frame !== undefined ? storedIndexOf(Number(fragment.frame)) : 0);
  const opened = sceneState();
  if (fragment.scrub !== undefined) {
    // Test hook (docs/viewer.md): after opening, move the timeline to a frame as a user would, so a
    // test sees the state before and after the timeline's own input handler ran.
    timeline.value = String(storedIndexOf(Number(fragment.scrub)));
    timeline.dispatchEvent(new Event('input'));
    writeState({ opened });
  } else {
    writeState();
  }
  if (fragment.play !== undefined) setPlaying(true);
  return null;

  // The live page: each record is appended (the oldest given up beyond the window) and shown,
  // unless the person moved the timeline back. Test hook `reads=A,B` (docs/live.md): the state at
  // the A-th frame received and at the B-th, then the page stops listening.
  function followStream() {
    let following = true;
    timeline.addEventListener('input', () => { following = Number(timeline.value) === N - 1; });
    const reads = (live.fragment.reads || '').split(',').filter((r) => r !== '').map(Number);
    let first = null;
    const check = (received) => {
      if (reads.length !== 2) return;
      if (received === reads[0]) first = sceneState();
      if (received === reads[1]) {
        live.source.close();
        writeState({ opened: first, frames_received: received, live: true });
      }
    };
    showFrame(0);
    writeState({ live: true });
    check(1);
    return {
      push(record, received) {
        if (values.length < windowFrames * F) {
          const room = new Float32Array(windowFrames * F);  // once: the window's whole size
          room.set(values.subarray(0, N * F));
          values = room;
        }
        if (N === windowFrames) values.copyWithin(0, F);
        else ++N;
        values.set(record, (N - 1) * F);
        distanceSeries = Array.from({ length: N }, (_, i) => at(i, 'mean_marker_distance', 0));
        timeline.max = String(N - 1);
        showFrame(following ? N - 1 : Math.max(current - (N === windowFrames ? 1 : 0), 0));
        check(received);
      },
    };
  }
}

try {
  const metaElement = document.getElementById('s2kf-meta');
  let data = null;
  if (metaElement && /"live"\s*:\s*true/.test(metaElement.textContent)) {
    startLive();
  } else {
    try {
      data = loadData();
    } catch (e) {
      fail(e.message);
    }
    if (data) main(data, null);
  }
} catch (e) {
  fail('The viewer failed: ' + (e && e.message ? e.message : e));
  throw e;
}
