// The 3D view of report.html: the map as points (coloured by height or intensity), the
// trajectory, keyframes and loop edges, with orbit / pan / zoom (three.js OrbitControls).
// The data are one base64 block (#view3d-data) laid out as #view3d-meta says.
(function () {
  'use strict';
  const root = document.getElementById('view3d');
  const canvas = document.getElementById('view3d-canvas');
  if (!root || !canvas || typeof THREE === 'undefined') return;
  const meta = JSON.parse(document.getElementById('view3d-meta').textContent);
  const text = atob(document.getElementById('view3d-data').textContent.trim());
  const bytes = new Uint8Array(text.length);
  for (let i = 0; i < text.length; ++i) bytes[i] = text.charCodeAt(i);
  const floats = (offset, count) => new Float32Array(bytes.buffer, offset * 4, count);
  const mapXyz = floats(0, meta.points * 3);
  const trajXyz = floats(meta.points * 3, meta.poses * 3);
  const keyXyz = floats((meta.points + meta.poses) * 3, meta.keyframes * 3);
  const loopXyz = floats((meta.points + meta.poses + meta.keyframes) * 3, meta.loops * 6);
  const intensity = new Uint8Array(bytes.buffer, (meta.points + meta.poses + meta.keyframes + 2 * meta.loops) * 12,
                                   meta.points);

  // Perceptually ordered colour map (viridis, 6 stops).
  const stops = [[68, 1, 84], [65, 68, 135], [42, 120, 142], [34, 168, 132], [122, 209, 81], [253, 231, 37]];
  function viridis(t, out, k) {
    t = Math.min(1, Math.max(0, t)) * (stops.length - 1);
    const i = Math.min(stops.length - 2, Math.floor(t)), f = t - i;
    for (let c = 0; c < 3; ++c) out[k + c] = (stops[i][c] + f * (stops[i + 1][c] - stops[i][c])) / 255;
  }
  const colors = new Float32Array(meta.points * 3);
  let colourMode = 'height', top = Math.min(meta.z_high, meta.cut_z);
  // Heights span the floor to the cut: what is shown uses the whole colour map.
  function colourBy(mode) {
    colourMode = mode;
    for (let i = 0; i < meta.points; ++i) {
      const t = mode === 'height' ? (mapXyz[3 * i + 2] - meta.z_low) / Math.max(1e-3, top - meta.z_low)
                                  : intensity[i] / 255;
      viridis(t, colors, 3 * i);
    }
  }
  colourBy('height');

  const renderer = new THREE.WebGLRenderer({canvas: canvas, antialias: true, preserveDrawingBuffer: true});
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setClearColor(0x14161a);
  renderer.localClippingEnabled = true;
  const scene = new THREE.Scene();
  const camera = new THREE.PerspectiveCamera(55, 1, 0.05, 5000);
  camera.up.set(0, 0, 1);

  const mapGeometry = new THREE.BufferGeometry();
  mapGeometry.setAttribute('position', new THREE.BufferAttribute(mapXyz, 3));
  const colorAttribute = new THREE.BufferAttribute(colors, 3);
  mapGeometry.setAttribute('color', colorAttribute);
  // Indoors the ceiling hides everything: the map is cut above a height the user can move, by
  // default 1 m above the trajectory.
  const cut = new THREE.Plane(new THREE.Vector3(0, 0, -1), meta.cut_z);
  const mapMaterial = new THREE.PointsMaterial(
      {size: 2, sizeAttenuation: false, vertexColors: THREE.VertexColors, clippingPlanes: [cut]});
  scene.add(new THREE.Points(mapGeometry, mapMaterial));

  const layers = {};
  function lineOf(xyz, color, segments) {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(xyz, 3));
    const m = new THREE.LineBasicMaterial({color: color, depthTest: false, transparent: true});
    const l = segments ? new THREE.LineSegments(g, m) : new THREE.Line(g, m);
    l.renderOrder = 1;
    scene.add(l);
    return l;
  }
  layers.trajectory = lineOf(trajXyz, 0xff4d4d, false);
  layers.loops = lineOf(loopXyz, 0x3ddc84, true);
  const keyGeometry = new THREE.BufferGeometry();
  keyGeometry.setAttribute('position', new THREE.BufferAttribute(keyXyz, 3));
  layers.keyframes = new THREE.Points(keyGeometry, new THREE.PointsMaterial(
      {size: 6, sizeAttenuation: false, color: 0xffd23f, depthTest: false, transparent: true}));
  layers.keyframes.renderOrder = 2;
  scene.add(layers.keyframes);

  // Start above and behind the map's centre, looking at it.
  const span = Math.max(meta.x_high - meta.x_low, meta.y_high - meta.y_low, 5);
  const centre = new THREE.Vector3((meta.x_low + meta.x_high) / 2, (meta.y_low + meta.y_high) / 2, meta.z_low);
  camera.position.set(centre.x - 0.25 * span, centre.y - 0.55 * span, centre.z + 0.5 * span);
  const controls = new THREE.OrbitControls(camera, canvas);
  controls.target.copy(centre);
  controls.screenSpacePanning = true;

  function resize() {
    const w = canvas.clientWidth, h = canvas.clientHeight;
    renderer.setSize(w, h, false);
    camera.aspect = w / Math.max(1, h);
    camera.updateProjectionMatrix();
  }
  function render() { renderer.render(scene, camera); }
  controls.addEventListener('change', render);
  window.addEventListener('resize', function () { resize(); render(); });

  root.querySelector('#view3d-colour').addEventListener('change', function (e) {
    colourBy(e.target.value);
    colorAttribute.needsUpdate = true;
    render();
  });
  root.querySelector('#view3d-size').addEventListener('input', function (e) {
    mapMaterial.size = Number(e.target.value);
    render();
  });
  const cutInput = root.querySelector('#view3d-cut');
  cutInput.min = meta.z_low;
  cutInput.max = meta.z_max + 0.01;
  cutInput.value = meta.cut_z;
  cutInput.addEventListener('input', function (e) {
    cut.constant = Number(e.target.value);
    top = Math.min(meta.z_high, cut.constant);
    if (colourMode === 'height') {
      colourBy('height');
      colorAttribute.needsUpdate = true;
    }
    render();
  });
  root.querySelectorAll('input[data-layer]').forEach(function (box) {
    box.addEventListener('change', function () { layers[box.dataset.layer].visible = box.checked; render(); });
  });

  resize();
  controls.update();
  render();
  // For tests and for the curious: how many pixels the first frame drew (0: a blank view).
  const gl = renderer.getContext();
  const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight, px = new Uint8Array(w * h * 4);
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
  let drawn = 0;
  for (let i = 0; i < px.length; i += 4)
    if (Math.abs(px[i] - 0x14) + Math.abs(px[i + 1] - 0x16) + Math.abs(px[i + 2] - 0x1a) > 24) ++drawn;
  root.dataset.drawnPixels = String(drawn);
  root.dataset.points = String(meta.points);
})();
