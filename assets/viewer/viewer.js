// crest view: the page's script. Reads the JSON in #crest-data, draws it with three.js
// (global THREE), and takes a profile from two clicks exactly as crest's metrics stage does
// (src/metrics/profile.rs: `line:X0,Y0,X1,Y1`, bilinear samples every min(dx, dy), mean line
// over blocks of 4096, Rz = mean of five sampling lengths' peak-to-valley heights).
// Test hook: `?crest-test=click:U0,V0,U1,V1` clicks at those fractions of the canvas and
// writes the result as JSON into #crest-test.
(function () {
  'use strict';
  const T = THREE;
  const D = JSON.parse(document.getElementById('crest-data').textContent);
  const $ = (id) => document.getElementById(id);

  function bytes(b64) {
    const s = atob(b64);
    const u = new Uint8Array(s.length);
    for (let i = 0; i < s.length; i++) u[i] = s.charCodeAt(i);
    return new DataView(u.buffer);
  }
  function f64(b64) {
    const dv = bytes(b64);
    const a = new Float64Array(dv.byteLength / 8);
    for (let i = 0; i < a.length; i++) a[i] = dv.getFloat64(8 * i, true);
    return a;
  }
  function f32(b64) {
    const dv = bytes(b64);
    const a = new Float64Array(dv.byteLength / 4);
    for (let i = 0; i < a.length; i++) a[i] = dv.getFloat32(4 * i, true);
    return a;
  }

  // Colour scale, sRGB stops: blue (low) → sky → green → yellow → red (high).
  const STOPS = [
    [0.0, [0.16, 0.22, 0.7]],
    [0.25, [0.1, 0.6, 0.85]],
    [0.5, [0.3, 0.75, 0.35]],
    [0.75, [0.95, 0.8, 0.2]],
    [1.0, [0.8, 0.15, 0.12]],
  ];
  function colour(t) {
    t = Math.min(1, Math.max(0, t));
    for (let k = 1; k < STOPS.length; k++) {
      if (t <= STOPS[k][0]) {
        const [t0, a] = STOPS[k - 1];
        const [t1, b] = STOPS[k];
        const u = (t - t0) / (t1 - t0);
        return [0, 1, 2].map((i) => a[i] + (b[i] - a[i]) * u);
      }
    }
    return STOPS[STOPS.length - 1][1];
  }
  const NAN_RGB = [0.62, 0.64, 0.66];

  function fmt(v, digits) {
    if (v === null || v === undefined || !Number.isFinite(v)) return '—';
    const a = Math.abs(v);
    if (a !== 0 && (a >= 1e5 || a < 1e-3)) return v.toExponential(3);
    return v.toFixed(digits === undefined ? 4 : digits);
  }

  // ---- the profile, as src/metrics/profile.rs computes it ----
  function bilinear(g, x, y) {
    x = Math.min(Math.max(x, 0), g.nx - 1);
    y = Math.min(Math.max(y, 0), g.ny - 1);
    const i = Math.floor(y);
    const j = Math.floor(x);
    const fy = y - i;
    const fx = x - j;
    const i1 = Math.min(i + 1, g.ny - 1);
    const j1 = Math.min(j + 1, g.nx - 1);
    const v = (r, c, w) => (w === 0 ? 0 : w * g.z[r * g.nx + c]);
    return (
      v(i, j, (1 - fy) * (1 - fx)) +
      v(i, j1, (1 - fy) * fx) +
      v(i1, j, fy * (1 - fx)) +
      v(i1, j1, fy * fx)
    );
  }
  // `line:` profile from (x0, y0) to (x1, y1), µm from the grid's node (0, 0).
  function lineProfile(g, x0, y0, x1, y1) {
    const ex = x1 - x0;
    const ey = y1 - y0;
    const len = Math.sqrt(ex * ex + ey * ey);
    const step = Math.min(g.dx, g.dy);
    if (!(len >= step)) return null;
    const c = ex / len;
    const s = ey / len;
    const n = Math.floor(len / step + 1e-9) + 1;
    const z = new Float64Array(n);
    for (let k = 0; k < n; k++) {
      const t = k * step;
      z[k] = bilinear(g, (x0 + t * c) / g.dx, (y0 + t * s) / g.dy);
    }
    return { z, step, len };
  }
  // Rz over five sampling lengths (numpy.array_split sections), heights about the mean.
  function rz(z) {
    const BLOCK = 4096;
    let sum = 0;
    let n = 0;
    for (let b = 0; b < z.length; b += BLOCK) {
      let s = 0;
      let c = 0;
      for (let i = b; i < Math.min(b + BLOCK, z.length); i++) {
        if (Number.isFinite(z[i])) {
          s += z[i];
          c += 1;
        }
      }
      sum += s;
      n += c;
    }
    const sections = 5;
    if (n < 2 || z.length < sections) return NaN;
    const mean = sum / n;
    const base = Math.floor(z.length / sections);
    const extra = z.length % sections;
    let sz = 0;
    let used = 0;
    let start = 0;
    for (let k = 0; k < sections; k++) {
      const len = base + (k < extra ? 1 : 0);
      let hi = -Infinity;
      let lo = Infinity;
      for (let i = start; i < start + len; i++) {
        const v = z[i] - mean;
        if (Number.isFinite(v)) {
          hi = Math.max(hi, v);
          lo = Math.min(lo, v);
        }
      }
      start += len;
      if (Number.isFinite(hi)) {
        sz += hi - lo;
        used += 1;
      }
    }
    return sz / used;
  }

  // ---- page text ----
  document.title = D.title;
  $('title').textContent = D.title;
  const table = $('params');
  for (const [name, value, unit] of D.params) {
    const tr = table.insertRow();
    tr.insertCell().textContent = name;
    const v = tr.insertCell();
    v.className = 'v';
    v.textContent = fmt(value);
    const u = tr.insertCell();
    u.className = 'u';
    u.textContent = unit;
  }

  // ---- data ----
  const isMap = D.kind === 'heightmap';
  let values; // heights coloured, µm
  let px, py; // lateral positions, scene units (µm for maps, mm for part maps)
  let normals = null;
  let full = null;
  let grid = null;
  if (isMap) {
    const d = D.display;
    values = f32(d.z_f32);
    grid = d;
    if (D.full_f64) {
      full = { nx: D.nx, ny: D.ny, dx: D.dx_um, dy: D.dy_um, z: f64(D.full_f64), ox: 0, oy: 0 };
    } else {
      // Too large to embed: the profile is taken from the displayed block means.
      full = {
        nx: d.nx, ny: d.ny, dx: D.dx_um * D.factor, dy: D.dy_um * D.factor,
        z: values, ox: d.xs_um[0], oy: d.ys_um[0],
      };
    }
    const shown = D.factor > 1 ? `, shown as ${d.nx} × ${d.ny} means of ${D.factor} × ${D.factor} nodes` : '';
    $('source').textContent =
      `${D.source} · field ${fmt((D.nx - 1) * D.dx_um, 0)} × ${fmt((D.ny - 1) * D.dy_um, 0)} µm, ` +
      `${D.nx} × ${D.ny} nodes at ${D.dx_um} × ${D.dy_um} µm, ` +
      `${D.valid} valid${shown} · origin (${D.x0_mm}, ${D.y0_mm}) mm`;
  } else {
    values = f32(D.h_f32);
    const xyz = f64(D.xyz_mm_f64);
    px = xyz;
    normals = D.n_f32 ? f32(D.n_f32) : null;
    const every = D.stride > 1 ? `, every ${D.stride}th of ${D.points} drawn` : '';
    $('source').textContent = `${D.source} · part map, ${D.shown} points${every}; colour: height along the normal`;
    $('profile').style.display = 'none';
    $('hint').textContent = 'drag: orbit · wheel: zoom · right- or shift-drag: pan';
  }
  let zmin = Infinity;
  let zmax = -Infinity;
  for (const v of values) {
    if (Number.isFinite(v)) {
      zmin = Math.min(zmin, v);
      zmax = Math.max(zmax, v);
    }
  }
  if (!Number.isFinite(zmin)) {
    zmin = 0;
    zmax = 1;
  }
  const zspan = zmax > zmin ? zmax - zmin : 1;
  const zmid = 0.5 * (zmin + zmax);
  const tOf = (v) => (v - zmin) / zspan;

  // Colour bar.
  (function () {
    const bar = $('bar');
    const ctx = bar.getContext('2d');
    for (let x = 0; x < bar.width; x++) {
      const c = colour(x / (bar.width - 1)).map((v) => Math.round(v * 255));
      ctx.fillStyle = `rgb(${c[0]},${c[1]},${c[2]})`;
      ctx.fillRect(x, 0, 1, bar.height);
    }
    const ticks = $('ticks');
    const digits = zspan >= 10 ? 1 : zspan >= 1 ? 2 : 3;
    for (let k = 0; k <= 4; k++) {
      const s = document.createElement('span');
      s.style.left = `${(k / 4) * (bar.width - 1) + 1}px`;
      s.textContent = (zmin + (k / 4) * zspan).toFixed(digits);
      ticks.appendChild(s);
    }
    $('unit').textContent = isMap
      ? 'height, µm' + (D.factor > 1 ? ' (range of the displayed block means)' : '')
      : 'height along the normal, µm (grey: not reached)';
  })();

  // ---- three.js scene ----
  const canvas = $('gl');
  const renderer = new T.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  renderer.setClearColor(0xeef1f4, 1);
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  const scene = new T.Scene();
  scene.add(new T.AmbientLight(0xffffff, 1.1));
  const sun = new T.DirectionalLight(0xffffff, 2.0);
  scene.add(sun);
  const camera = new T.PerspectiveCamera(35, 1, 1e-3, 1e7);
  camera.up.set(0, 0, 1);

  let cx = 0;
  let cy = 0;
  let cz = 0;
  let size = 1;
  let diag = 1;
  let exag0 = 1;
  let exag = 1;
  let object;
  let positions;

  const col = (v) => {
    const c = new T.Color();
    const rgb = Number.isFinite(v) ? colour(tOf(v)) : NAN_RGB;
    c.setRGB(rgb[0], rgb[1], rgb[2], T.SRGBColorSpace);
    return c;
  };

  if (isMap) {
    const nx = grid.nx;
    const ny = grid.ny;
    const xs = grid.xs_um;
    const ys = grid.ys_um;
    cx = 0.5 * (xs[0] + xs[nx - 1]);
    cy = 0.5 * (ys[0] + ys[ny - 1]);
    size = Math.max(xs[nx - 1] - xs[0], ys[ny - 1] - ys[0], 1e-9);
    diag = Math.hypot(xs[nx - 1] - xs[0], ys[ny - 1] - ys[0], 0.2 * size);
    exag0 = (0.2 * size) / zspan;
    positions = new Float32Array(nx * ny * 3);
    const colours = new Float32Array(nx * ny * 3);
    for (let r = 0; r < ny; r++) {
      for (let c = 0; c < nx; c++) {
        const k = r * nx + c;
        positions[3 * k] = xs[c] - cx;
        positions[3 * k + 1] = ys[r] - cy;
        const rgb = col(values[k]);
        colours[3 * k] = rgb.r;
        colours[3 * k + 1] = rgb.g;
        colours[3 * k + 2] = rgb.b;
      }
    }
    const index = [];
    const ok = (k) => Number.isFinite(values[k]);
    for (let r = 0; r + 1 < ny; r++) {
      for (let c = 0; c + 1 < nx; c++) {
        const a = r * nx + c;
        const b = a + 1;
        const d = a + nx;
        const e = d + 1;
        if (ok(a) && ok(b) && ok(e)) index.push(a, b, e);
        if (ok(a) && ok(e) && ok(d)) index.push(a, e, d);
      }
    }
    const geo = new T.BufferGeometry();
    geo.setAttribute('position', new T.BufferAttribute(positions, 3));
    geo.setAttribute('color', new T.BufferAttribute(colours, 3));
    geo.setIndex(index);
    object = new T.Mesh(
      geo,
      new T.MeshLambertMaterial({ vertexColors: true, side: T.DoubleSide }),
    );
  } else {
    const n = values.length;
    let lo = [Infinity, Infinity, Infinity];
    let hi = [-Infinity, -Infinity, -Infinity];
    for (let k = 0; k < n; k++) {
      for (let i = 0; i < 3; i++) {
        lo[i] = Math.min(lo[i], px[3 * k + i]);
        hi[i] = Math.max(hi[i], px[3 * k + i]);
      }
    }
    [cx, cy, cz] = [0, 1, 2].map((i) => 0.5 * (lo[i] + hi[i]));
    size = Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-9);
    diag = Math.max(Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]), 1e-9);
    const amax = Math.max(Math.abs(zmin), Math.abs(zmax), 1e-9);
    exag0 = (0.01 * size) / (amax * 1e-3);
    positions = new Float32Array(n * 3);
    const colours = new Float32Array(n * 3);
    for (let k = 0; k < n; k++) {
      const rgb = col(values[k]);
      colours[3 * k] = rgb.r;
      colours[3 * k + 1] = rgb.g;
      colours[3 * k + 2] = rgb.b;
    }
    const geo = new T.BufferGeometry();
    geo.setAttribute('position', new T.BufferAttribute(positions, 3));
    geo.setAttribute('color', new T.BufferAttribute(colours, 3));
    const spacing = size / Math.sqrt(Math.max(n, 1));
    object = new T.Points(geo, new T.PointsMaterial({ size: 1.2 * spacing, vertexColors: true }));
  }
  scene.add(object);

  // Heights in scene units at the current exaggeration.
  function sceneZ(v) {
    return isMap ? (v - zmid) * exag : 0;
  }
  function applyExaggeration() {
    const geo = object.geometry;
    if (isMap) {
      for (let k = 0; k < values.length; k++) {
        positions[3 * k + 2] = Number.isFinite(values[k]) ? sceneZ(values[k]) : 0;
      }
      geo.attributes.position.needsUpdate = true;
      geo.computeVertexNormals();
    } else {
      for (let k = 0; k < values.length; k++) {
        const h = Number.isFinite(values[k]) ? values[k] * 1e-3 * exag : 0;
        for (let i = 0; i < 3; i++) {
          const nrm = normals ? normals[3 * k + i] : i === 2 ? 1 : 0;
          positions[3 * k + i] = px[3 * k + i] - [cx, cy, cz][i] + h * nrm;
        }
      }
      geo.attributes.position.needsUpdate = true;
    }
    geo.computeBoundingSphere();
    $('exag-value').textContent = `×${exag >= 10 ? exag.toFixed(0) : exag.toPrecision(2)}`;
  }

  // ---- camera: orbit about a target, zoom, pan ----
  const target = new T.Vector3(0, 0, 0);
  let azimuth = -2.0;
  let polar = 0.95;
  // Far enough for the bounding box's diagonal to fit the view (field of view 35°).
  let radius = 1.7 * diag;
  function placeCamera() {
    const s = Math.sin(polar);
    camera.position.set(
      target.x + radius * s * Math.cos(azimuth),
      target.y + radius * s * Math.sin(azimuth),
      target.z + radius * Math.cos(polar),
    );
    camera.near = radius * 1e-3;
    camera.far = radius * 100;
    camera.lookAt(target);
    camera.updateProjectionMatrix();
    sun.position.copy(camera.position).add(new T.Vector3(-0.6 * radius, 0.4 * radius, radius));
    sun.target = object;
  }
  function resize() {
    const w = canvas.clientWidth || 800;
    const h = canvas.clientHeight || 600;
    renderer.setSize(w, h, false);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
  }
  function render() {
    placeCamera();
    renderer.render(scene, camera);
  }

  // ---- profile picking ----
  const raycaster = new T.Raycaster();
  let picks = [];
  let marks = [];
  let lastProfile = null;
  function clearMarks() {
    for (const m of marks) {
      scene.remove(m);
      m.geometry.dispose();
    }
    marks = [];
  }
  function pickAt(clientX, clientY) {
    const r = canvas.getBoundingClientRect();
    const ndc = new T.Vector2(
      ((clientX - r.left) / r.width) * 2 - 1,
      -((clientY - r.top) / r.height) * 2 + 1,
    );
    raycaster.setFromCamera(ndc, camera);
    const hit = raycaster.intersectObject(object, false)[0];
    if (!hit) return null;
    return { x: hit.point.x + cx, y: hit.point.y + cy };
  }
  function marker(x, y, z) {
    const m = new T.Mesh(
      new T.SphereGeometry(0.012 * size, 16, 12),
      new T.MeshBasicMaterial({ color: 0x111111 }),
    );
    m.position.set(x - cx, y - cy, z);
    scene.add(m);
    marks.push(m);
  }
  function heightAt(x, y) {
    const g = full;
    const v = bilinear(g, (x - g.ox) / g.dx, (y - g.oy) / g.dy);
    return Number.isFinite(v) ? v : zmid;
  }
  function onClick(clientX, clientY) {
    if (!isMap) return;
    const p = pickAt(clientX, clientY);
    if (!p) return;
    if (picks.length === 2) {
      picks = [];
      clearMarks();
    }
    picks.push(p);
    marker(p.x, p.y, sceneZ(heightAt(p.x, p.y)));
    if (picks.length === 2) showProfile();
    render();
  }
  function showProfile() {
    const [a, b] = picks;
    const g = full;
    const prof = lineProfile(g, a.x - g.ox, a.y - g.oy, b.x - g.ox, b.y - g.oy);
    if (!prof) {
      $('profile-text').textContent = 'The two points are closer than one grid step.';
      lastProfile = null;
      return;
    }
    const value = rz(prof.z);
    const line = `line:${a.x},${a.y},${b.x},${b.y}`;
    lastProfile = { line, rz: value, samples: prof.z.length, step_um: prof.step, picks: [a, b] };
    const basis = D.full_f64
      ? 'full-resolution map'
      : `displayed ${D.factor} × ${D.factor} block means (the map is too large to embed)`;
    $('profile-text').textContent =
      `Rz ${fmt(value)} µm over ${fmt(prof.len, 1)} µm (${prof.z.length} samples every ` +
      `${prof.step} µm, 5 sampling lengths, ${basis}).`;
    $('profile-cmd').textContent =
      D.full_f64 && D.file ? `same as: crest metrics ${D.file} --profile ${line} --params Rz` : '';
    // Chart.
    const ch = $('chart');
    const ctx = ch.getContext('2d');
    ctx.clearRect(0, 0, ch.width, ch.height);
    let lo = Infinity;
    let hi = -Infinity;
    for (const v of prof.z) {
      if (Number.isFinite(v)) {
        lo = Math.min(lo, v);
        hi = Math.max(hi, v);
      }
    }
    const m = { l: 40, r: 6, t: 8, b: 20 };
    const W = ch.width - m.l - m.r;
    const H = ch.height - m.t - m.b;
    const span = hi > lo ? hi - lo : 1;
    ctx.strokeStyle = '#9aa4ae';
    ctx.strokeRect(m.l, m.t, W, H);
    ctx.fillStyle = '#56606b';
    ctx.font = '10px sans-serif';
    ctx.fillText(`${hi.toFixed(2)}`, 2, m.t + 8);
    ctx.fillText(`${lo.toFixed(2)}`, 2, m.t + H);
    ctx.fillText('µm', 2, m.t + H / 2 + 4);
    ctx.fillText('0', m.l, ch.height - 6);
    ctx.fillText(`${prof.len.toFixed(0)} µm`, m.l + W - 40, ch.height - 6);
    ctx.strokeStyle = '#1d4f91';
    ctx.lineWidth = 1.2;
    ctx.beginPath();
    let pen = false;
    prof.z.forEach((v, k) => {
      if (!Number.isFinite(v)) {
        pen = false;
        return;
      }
      const x = m.l + (W * k) / Math.max(prof.z.length - 1, 1);
      const y = m.t + H * (1 - (v - lo) / span);
      if (pen) ctx.lineTo(x, y);
      else ctx.moveTo(x, y);
      pen = true;
    });
    ctx.stroke();
    // The line on the surface.
    const pts = [];
    const ex = (b.x - a.x) / prof.len;
    const ey = (b.y - a.y) / prof.len;
    prof.z.forEach((v, k) => {
      const t = k * prof.step;
      const z = Number.isFinite(v) ? v : zmid;
      pts.push(new T.Vector3(a.x + t * ex - cx, a.y + t * ey - cy, sceneZ(z) + 0.002 * size));
    });
    const geo = new T.BufferGeometry().setFromPoints(pts);
    const l = new T.Line(geo, new T.LineBasicMaterial({ color: 0x111111 }));
    scene.add(l);
    marks.push(l);
  }
  function redrawProfileLine() {
    if (picks.length === 2) {
      const keep = picks;
      clearMarks();
      picks = keep;
      for (const p of picks) marker(p.x, p.y, sceneZ(heightAt(p.x, p.y)));
      showProfile();
    } else if (picks.length === 1) {
      clearMarks();
      marker(picks[0].x, picks[0].y, sceneZ(heightAt(picks[0].x, picks[0].y)));
    }
  }
  if (isMap) $('profile-text').textContent = 'Click two points on the surface.';

  // ---- input ----
  let drag = null;
  canvas.addEventListener('pointerdown', (e) => {
    drag = { x: e.clientX, y: e.clientY, x0: e.clientX, y0: e.clientY, pan: e.button === 2 || e.shiftKey };
  });
  window.addEventListener('pointermove', (e) => {
    if (!drag) return;
    const dx = e.clientX - drag.x;
    const dy = e.clientY - drag.y;
    drag.x = e.clientX;
    drag.y = e.clientY;
    if (drag.pan) {
      const k = (radius * 1.2) / (canvas.clientHeight || 600);
      const right = new T.Vector3().setFromMatrixColumn(camera.matrixWorld, 0);
      const up = new T.Vector3().setFromMatrixColumn(camera.matrixWorld, 1);
      target.addScaledVector(right, -dx * k).addScaledVector(up, dy * k);
    } else {
      azimuth -= dx * 0.008;
      polar = Math.min(Math.max(polar - dy * 0.008, 0.02), Math.PI - 0.02);
    }
    render();
  });
  window.addEventListener('pointerup', (e) => {
    if (!drag) return;
    const moved = Math.hypot(e.clientX - drag.x0, e.clientY - drag.y0);
    const wasPan = drag.pan;
    drag = null;
    if (moved < 4 && e.button === 0 && !wasPan) onClick(e.clientX, e.clientY);
  });
  canvas.addEventListener('contextmenu', (e) => e.preventDefault());
  canvas.addEventListener(
    'wheel',
    (e) => {
      e.preventDefault();
      radius *= Math.exp(e.deltaY * 0.001);
      render();
    },
    { passive: false },
  );
  $('exag').addEventListener('input', () => {
    exag = exag0 * Math.pow(10, Number($('exag').value));
    applyExaggeration();
    redrawProfileLine();
    render();
  });
  window.addEventListener('resize', () => {
    resize();
    render();
  });

  exag = exag0;
  resize();
  applyExaggeration();
  render();

  // ---- test hook ----
  const q = new URLSearchParams(location.search).get('crest-test');
  if (q !== null) {
    const r = canvas.getBoundingClientRect();
    const out = { canvas: { x: r.left, y: r.top, w: r.width, h: r.height } };
    const m = /^click:([^,]+),([^,]+),([^,]+),([^,]+)$/.exec(q);
    if (m) {
      const u = m.slice(1).map(Number);
      for (const [fu, fv] of [[u[0], u[1]], [u[2], u[3]]]) {
        const init = {
          clientX: r.left + fu * r.width,
          clientY: r.top + fv * r.height,
          button: 0,
          bubbles: true,
        };
        canvas.dispatchEvent(new PointerEvent('pointerdown', init));
        window.dispatchEvent(new PointerEvent('pointerup', init));
      }
      out.profile = lastProfile && {
        line: lastProfile.line,
        rz: String(lastProfile.rz),
        samples: lastProfile.samples,
        step_um: lastProfile.step_um,
      };
    }
    out.zmin = zmin;
    out.zmax = zmax;
    out.triangles = isMap ? object.geometry.index.count / 3 : 0;
    out.errors = window.crestErrors;
    $('crest-test').textContent = JSON.stringify(out);
  }
})();
