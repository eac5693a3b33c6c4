// pfaff's trajectory viewer: a small WebGL2 renderer written for pfaff (MIT, as pfaff).
// It reads the scene from the JSON block #pfaff-data of its page and fetches nothing:
// particles as point sprites shaded as spheres, instanced ellipsoids and boxes (bodies) and rods (links), lit by two
// directional lights; orbit with the mouse, zoom with the wheel, play / pause / scrub / speed.
(function () {
  "use strict";
  var D = JSON.parse(document.getElementById("pfaff-data").textContent);
  var root = document.getElementById("pfaff-viewer");
  var canvas = root.querySelector("canvas");
  var label = root.querySelector(".pfaff-time");
  var slider = root.querySelector(".pfaff-scrub");
  var button = root.querySelector(".pfaff-play");
  var speedSel = root.querySelector(".pfaff-speed");

  function bytes(b64) {
    var s = atob(b64), u = new Uint8Array(s.length);
    for (var i = 0; i < s.length; i++) u[i] = s.charCodeAt(i);
    return u.buffer;
  }
  function floats(b64) { return new Float32Array(bytes(b64)); }
  var T = new Float64Array(bytes(D.t)), F = T.length, P = D.npoints, B = D.nbodies, dim = D.dim;
  var PTS = floats(D.points), CEN = floats(D.centres), QUA = floats(D.quaternions);
  var NA = D.narrows, ARR = floats(D.arrows);
  var links = D.links, radius = D.radius, pcol = D.point_colours, half = D.half;
  var up = D.up_matrix; // model -> world (z up), row-major 3x3

  var gl = canvas.getContext("webgl2", { antialias: true, preserveDrawingBuffer: true });
  if (!gl) {
    label.textContent = "this browser has no WebGL2: the scene cannot be drawn";
    root.dataset.ready = "no-webgl";
    return;
  }

  // ------------------------------------------------------------------ meshes (unit solids)
  function sphereMesh(nu, nv) {
    var v = [];
    function pt(i, j) {
      var th = Math.PI * j / nv, ph = 2 * Math.PI * i / nu;
      var x = Math.sin(th) * Math.cos(ph), y = Math.sin(th) * Math.sin(ph), z = Math.cos(th);
      v.push(x, y, z, x, y, z);
    }
    for (var j = 0; j < nv; j++) for (var i = 0; i < nu; i++) {
      pt(i, j); pt(i, j + 1); pt(i + 1, j + 1);
      pt(i, j); pt(i + 1, j + 1); pt(i + 1, j);
    }
    return v;
  }
  function boxMesh() {
    var v = [], f = [[0, 1, 2], [1, 2, 0], [2, 0, 1]];
    for (var a = 0; a < 3; a++) for (var s = -1; s <= 1; s += 2) {
      var c = [[-1, -1], [1, -1], [1, 1], [-1, -1], [1, 1], [-1, 1]];
      for (var k = 0; k < 6; k++) {
        var p = [0, 0, 0], n = [0, 0, 0];
        p[f[a][0]] = s; p[f[a][1]] = c[k][0] * s; p[f[a][2]] = c[k][1];
        n[f[a][0]] = s;
        v.push(p[0], p[1], p[2], n[0], n[1], n[2]);
      }
    }
    return v;
  }
  function coneMesh(nu) { // radius 1 at z = 0 to the tip at z = 1
    var v = [], k = 1 / Math.SQRT2;
    for (var i = 0; i < nu; i++) {
      var a0 = 2 * Math.PI * i / nu, a1 = 2 * Math.PI * (i + 1) / nu;
      var c0 = Math.cos(a0), s0 = Math.sin(a0), c1 = Math.cos(a1), s1 = Math.sin(a1);
      v.push(c0, s0, 0, c0 * k, s0 * k, k, c1, s1, 0, c1 * k, s1 * k, k, 0, 0, 1, c0 * k, s0 * k, k);
      v.push(c0, s0, 0, 0, 0, -1, c1, s1, 0, 0, 0, -1, 0, 0, 0, 0, 0, -1);
    }
    return v;
  }
  function rodMesh(nu) { // a cylinder of radius 1 from z = 0 to z = 1
    var v = [];
    for (var i = 0; i < nu; i++) {
      var a0 = 2 * Math.PI * i / nu, a1 = 2 * Math.PI * (i + 1) / nu;
      var c0 = Math.cos(a0), s0 = Math.sin(a0), c1 = Math.cos(a1), s1 = Math.sin(a1);
      v.push(c0, s0, 0, c0, s0, 0, c1, s1, 0, c1, s1, 0, c1, s1, 1, c1, s1, 0);
      v.push(c0, s0, 0, c0, s0, 0, c1, s1, 1, c1, s1, 0, c0, s0, 1, c0, s0, 0);
    }
    return v;
  }

  // ------------------------------------------------------------------ shaders
  var VS = "#version 300 es\n" +
    "layout(location=0) in vec3 pos; layout(location=1) in vec3 nrm;\n" +
    "layout(location=2) in vec3 c0; layout(location=3) in vec3 c1; layout(location=4) in vec3 c2;\n" +
    "layout(location=5) in vec3 tr; layout(location=6) in vec3 col;\n" +
    "uniform mat4 vp; out vec3 vn; out vec3 vc;\n" +
    "void main() { mat3 M = mat3(c0, c1, c2);\n" +
    "  vec3 s = max(vec3(dot(c0, c0), dot(c1, c1), dot(c2, c2)), vec3(1e-30));\n" +
    "  vn = M * (nrm / s); vc = col; gl_Position = vp * vec4(M * pos + tr, 1.0); }\n";
  var FS = "#version 300 es\nprecision mediump float;\n" +
    "in vec3 vn; in vec3 vc; out vec4 o;\n" +
    "void main() { vec3 n = normalize(vn);\n" +
    "  float d = max(dot(n, normalize(vec3(0.4, -0.5, 0.8))), 0.0);\n" +
    "  float e = max(dot(n, normalize(vec3(-0.6, 0.4, 0.2))), 0.0);\n" +
    "  o = vec4(vc * (0.32 + 0.6 * d + 0.22 * e), 1.0); }\n";
  // Particles: one point each, drawn as a lit sphere by its fragment shader (an impostor), so a
  // ring of a thousand particles costs a thousand vertices.
  var PVS = "#version 300 es\n" +
    "layout(location=0) in vec3 pos; layout(location=1) in float rad; layout(location=2) in vec3 col;\n" +
    "uniform mat4 vp; uniform float scale; out vec3 vc;\n" +
    "void main() { vc = col; gl_Position = vp * vec4(pos, 1.0);\n" +
    "  gl_PointSize = rad > 0.0 ? max(2.0, 2.0 * rad * scale / gl_Position.w) : 0.0; }\n";
  var PFS = "#version 300 es\nprecision mediump float;\n" +
    "in vec3 vc; out vec4 o;\n" +
    "void main() { vec2 d = 2.0 * gl_PointCoord - 1.0; float r2 = dot(d, d);\n" +
    "  if (r2 > 1.0) discard;\n" +
    "  vec3 n = vec3(d.x, -d.y, sqrt(1.0 - r2));\n" +
    "  float l = max(dot(n, normalize(vec3(-0.3, 0.5, 0.8))), 0.0);\n" +
    "  o = vec4(vc * (0.35 + 0.7 * l), 1.0); }\n";
  function shader(type, src) {
    var s = gl.createShader(type);
    gl.shaderSource(s, src); gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
    return s;
  }
  var prog = gl.createProgram();
  gl.attachShader(prog, shader(gl.VERTEX_SHADER, VS));
  gl.attachShader(prog, shader(gl.FRAGMENT_SHADER, FS));
  gl.linkProgram(prog);
  var vpLoc = gl.getUniformLocation(prog, "vp");
  var pprog = gl.createProgram();
  gl.attachShader(pprog, shader(gl.VERTEX_SHADER, PVS));
  gl.attachShader(pprog, shader(gl.FRAGMENT_SHADER, PFS));
  gl.linkProgram(pprog);
  var pvpLoc = gl.getUniformLocation(pprog, "vp"), scaleLoc = gl.getUniformLocation(pprog, "scale");
  var dotVao = gl.createVertexArray(), dotBuf = gl.createBuffer(), dotData = new Float32Array(Math.max(P, 1) * 7);
  gl.bindVertexArray(dotVao);
  gl.bindBuffer(gl.ARRAY_BUFFER, dotBuf);
  gl.bufferData(gl.ARRAY_BUFFER, dotData.byteLength, gl.DYNAMIC_DRAW);
  gl.enableVertexAttribArray(0); gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 28, 0);
  gl.enableVertexAttribArray(1); gl.vertexAttribPointer(1, 1, gl.FLOAT, false, 28, 12);
  gl.enableVertexAttribArray(2); gl.vertexAttribPointer(2, 3, gl.FLOAT, false, 28, 16);
  gl.bindVertexArray(null);

  // One drawable per mesh: its vertices and a per-instance buffer of 15 floats
  // (three scaled axes, translation, colour).
  function drawable(verts, count) {
    var vao = gl.createVertexArray();
    gl.bindVertexArray(vao);
    var vb = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, vb);
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(verts), gl.STATIC_DRAW);
    gl.enableVertexAttribArray(0); gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 24, 0);
    gl.enableVertexAttribArray(1); gl.vertexAttribPointer(1, 3, gl.FLOAT, false, 24, 12);
    var data = new Float32Array(Math.max(count, 1) * 15);
    var ib = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, ib);
    gl.bufferData(gl.ARRAY_BUFFER, data.byteLength, gl.DYNAMIC_DRAW);
    for (var a = 0; a < 5; a++) {
      gl.enableVertexAttribArray(2 + a);
      gl.vertexAttribPointer(2 + a, 3, gl.FLOAT, false, 60, 12 * a);
      gl.vertexAttribDivisor(2 + a, 1);
    }
    gl.bindVertexArray(null);
    return { vao: vao, ib: ib, data: data, n: verts.length / 6, count: count, used: 0 };
  }
  var fine = sphereMesh(24, 14);
  var kinds = D.kinds;
  var nEll = kinds.filter(function (k) { return k === "ellipsoid"; }).length;
  var GRID = D.ground === null ? 0 : 2 * 21;
  var ells = drawable(fine, nEll);
  var boxes = drawable(boxMesh(), B - nEll), rods = drawable(rodMesh(12), links.length + GRID + NA);
  var heads = drawable(coneMesh(12), NA);

  // ------------------------------------------------------------------ the scene at time t
  function put(d, c0, c1, c2, p, col) {
    var o = d.used * 15, a = d.data;
    a[o] = c0[0]; a[o + 1] = c0[1]; a[o + 2] = c0[2];
    a[o + 3] = c1[0]; a[o + 4] = c1[1]; a[o + 5] = c1[2];
    a[o + 6] = c2[0]; a[o + 7] = c2[1]; a[o + 8] = c2[2];
    a[o + 9] = p[0]; a[o + 10] = p[1]; a[o + 11] = p[2];
    a[o + 12] = col[0]; a[o + 13] = col[1]; a[o + 14] = col[2];
    d.used++;
  }
  function world(v) { // model coordinates -> world (z up)
    return [up[0] * v[0] + up[1] * v[1] + up[2] * v[2],
            up[3] * v[0] + up[4] * v[1] + up[5] * v[2],
            up[6] * v[0] + up[7] * v[1] + up[8] * v[2]];
  }
  function frameAt(t) {
    var lo = 0, hi = F - 1;
    if (t <= T[0] || F === 1) return [0, 0, 0];
    if (t >= T[F - 1]) return [F - 1, F - 1, 0];
    while (hi - lo > 1) { var m = (lo + hi) >> 1; if (T[m] <= t) lo = m; else hi = m; }
    return [lo, hi, (t - T[lo]) / (T[hi] - T[lo])];
  }
  function point(fr, k) {
    var i = fr[0], j = fr[1], s = fr[2], v = [0, 0, 0];
    for (var c = 0; c < dim; c++) {
      var a = PTS[(i * P + k) * dim + c], b = PTS[(j * P + k) * dim + c];
      v[c] = a + s * (b - a);
    }
    return world(v);
  }
  function body(fr, k) { // centre, and the rotation (nlerp of the quaternions) as columns
    var i = fr[0], j = fr[1], s = fr[2], c = [0, 0, 0], q = [0, 0, 0, 0], dot = 0;
    for (var a = 0; a < 3; a++) c[a] = CEN[(i * B + k) * 3 + a] * (1 - s) + CEN[(j * B + k) * 3 + a] * s;
    for (a = 0; a < 4; a++) dot += QUA[(i * B + k) * 4 + a] * QUA[(j * B + k) * 4 + a];
    var sg = dot < 0 ? -1 : 1, nq = 0;
    for (a = 0; a < 4; a++) {
      q[a] = QUA[(i * B + k) * 4 + a] * (1 - s) + sg * QUA[(j * B + k) * 4 + a] * s;
      nq += q[a] * q[a];
    }
    nq = Math.sqrt(nq) || 1;
    var w = q[0] / nq, x = q[1] / nq, y = q[2] / nq, z = q[3] / nq;
    var cols = [[1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)],
                [2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)],
                [2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)]];
    return [world(c), cols.map(world)];
  }
  var bodyColours = [[0.85, 0.45, 0.15], [0.2, 0.6, 0.35], [0.55, 0.35, 0.7], [0.8, 0.25, 0.3],
                     [0.25, 0.55, 0.75], [0.7, 0.6, 0.2]];
  var rodColour = [0.35, 0.35, 0.38];
  var lo3 = [0, 0, 0], hi3 = [0, 0, 0];
  function grow(p, r) {
    for (var a = 0; a < 3; a++) { lo3[a] = Math.min(lo3[a], p[a] - r); hi3[a] = Math.max(hi3[a], p[a] + r); }
  }
  function grid(c) { // lines of the ground plane z = D.ground around c, every D.spacing
    var s = D.spacing, n = (GRID / 2 - 1) / 2, gx = Math.round(c[0] / s) * s, gy = Math.round(c[1] / s) * s;
    var w = 0.004 * extent, L = 2 * n * s, g = [0.8, 0.8, 0.78];
    for (var i = -n; i <= n; i++) {
      put(rods, [w, 0, 0], [0, 0, w], [0, L, 0], [gx + i * s, gy - n * s, D.ground], g);
      put(rods, [0, w, 0], [0, 0, w], [L, 0, 0], [gx - n * s, gy + i * s, D.ground], g);
    }
  }
  function along(d, L) { // two unit vectors across the direction d of length L
    var e = Math.abs(d[0]) < 0.9 * L ? [1, 0, 0] : [0, 1, 0];
    var u = [d[1] * e[2] - d[2] * e[1], d[2] * e[0] - d[0] * e[2], d[0] * e[1] - d[1] * e[0]];
    var nu = Math.hypot(u[0], u[1], u[2]);
    u = [u[0] / nu, u[1] / nu, u[2] / nu];
    return [u, [(d[1] * u[2] - d[2] * u[1]) / L, (d[2] * u[0] - d[0] * u[2]) / L,
                (d[0] * u[1] - d[1] * u[0]) / L]];
  }
  function arrow(p, d, col) {
    var L = Math.hypot(d[0], d[1], d[2]);
    if (!(L > 0)) return;
    var uv = along(d, L), u = uv[0], v = uv[1], h = Math.min(0.3 * L, 0.06 * extent), r = h / 3;
    var s = (L - h) / L, w = 0.4 * r;
    put(rods, [u[0] * w, u[1] * w, u[2] * w], [v[0] * w, v[1] * w, v[2] * w], [d[0] * s, d[1] * s, d[2] * s], p, col);
    put(heads, [u[0] * r, u[1] * r, u[2] * r], [v[0] * r, v[1] * r, v[2] * r], [d[0] * h / L, d[1] * h / L, d[2] * h / L],
        [p[0] + d[0] * s, p[1] + d[1] * s, p[2] + d[2] * s], col);
  }
  function fill(t) {
    var fr = frameAt(t), k, P3 = [];
    lo3 = [Infinity, Infinity, Infinity]; hi3 = [-Infinity, -Infinity, -Infinity];
    ells.used = boxes.used = rods.used = heads.used = 0;
    for (k = 0; k < P; k++) {
      var p = point(fr, k), r = radius[k], o = 7 * k;
      P3.push(p);
      if (r > 0) grow(p, r);
      dotData[o] = p[0]; dotData[o + 1] = p[1]; dotData[o + 2] = p[2]; dotData[o + 3] = r;
      dotData[o + 4] = pcol[k][0]; dotData[o + 5] = pcol[k][1]; dotData[o + 6] = pcol[k][2];
    }
    for (k = 0; k < B; k++) {
      var b = body(fr, k), h = half[k], cl = bodyColours[k % bodyColours.length];
      var ax = b[1].map(function (v, a) { return [v[0] * h[a], v[1] * h[a], v[2] * h[a]]; });
      put(kinds[k] === "ellipsoid" ? ells : boxes, ax[0], ax[1], ax[2], b[0], cl);
      grow(b[0], Math.max(h[0], h[1], h[2]));
    }
    var origin = world([0, 0, 0]), rr = D.rod_radius;
    for (k = 0; k < links.length; k++) {
      var pa = links[k][0] < 0 ? origin : P3[links[k][0]];
      var pb = links[k][1] < 0 ? origin : P3[links[k][1]];
      var d = [pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]];
      var L = Math.hypot(d[0], d[1], d[2]);
      if (!(L > 0)) { put(rods, [0, 0, 0], [0, 0, 0], [0, 0, 0], pa, rodColour); continue; }
      var uv = along(d, L), u = uv[0], v = uv[1];
      put(rods, [u[0] * rr, u[1] * rr, u[2] * rr], [v[0] * rr, v[1] * rr, v[2] * rr], d, pa, rodColour);
    }
    for (k = 0; k < NA; k++) {
      var i0 = (fr[0] * NA + k) * 6, i1 = (fr[1] * NA + k) * 6, f = fr[2], g = [];
      for (var c = 0; c < 6; c++) g.push(ARR[i0 + c] * (1 - f) + ARR[i1 + c] * f);
      var sc = D.arrow_scale;
      arrow(world([g[0], g[1], g[2]]), world([g[3] * sc, g[4] * sc, g[5] * sc]), [0.85, 0.1, 0.1]);
    }
    if (D.follow && lo3[0] <= hi3[0]) cam.centre = [(lo3[0] + hi3[0]) / 2, (lo3[1] + hi3[1]) / 2, (lo3[2] + hi3[2]) / 2];
    if (GRID) grid(cam.centre);
  }

  // ------------------------------------------------------------------ camera
  var cam = { yaw: D.view[0], pitch: D.view[1], dist: 1, centre: world(D.centre) };
  var extent = D.extent;
  function perspective(fovy, aspect, near, far) {
    var f = 1 / Math.tan(fovy / 2), nf = 1 / (near - far);
    return [f / aspect, 0, 0, 0, 0, f, 0, 0, 0, 0, (far + near) * nf, -1, 0, 0, 2 * far * near * nf, 0];
  }
  function lookAt(eye, at) {
    var z = [eye[0] - at[0], eye[1] - at[1], eye[2] - at[2]], n = Math.hypot(z[0], z[1], z[2]);
    z = [z[0] / n, z[1] / n, z[2] / n];
    var upv = Math.abs(z[2]) > 0.999 ? [0, 1, 0] : [0, 0, 1];
    var x = [upv[1] * z[2] - upv[2] * z[1], upv[2] * z[0] - upv[0] * z[2], upv[0] * z[1] - upv[1] * z[0]];
    n = Math.hypot(x[0], x[1], x[2]); x = [x[0] / n, x[1] / n, x[2] / n];
    var y = [z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2], z[0] * x[1] - z[1] * x[0]];
    function d(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
    return [x[0], y[0], z[0], 0, x[1], y[1], z[1], 0, x[2], y[2], z[2], 0, -d(x, eye), -d(y, eye), -d(z, eye), 1];
  }
  function mul(a, b) {
    var o = new Float32Array(16);
    for (var c = 0; c < 4; c++) for (var r = 0; r < 4; r++) {
      var s = 0;
      for (var k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k];
      o[c * 4 + r] = s;
    }
    return o;
  }

  // ------------------------------------------------------------------ drawing and playback
  function draw(t) {
    var w = canvas.clientWidth, h = canvas.clientHeight, dpr = window.devicePixelRatio || 1;
    if (canvas.width !== Math.round(w * dpr) || canvas.height !== Math.round(h * dpr)) {
      canvas.width = Math.round(w * dpr); canvas.height = Math.round(h * dpr);
    }
    gl.viewport(0, 0, canvas.width, canvas.height);
    gl.clearColor(0.97, 0.97, 0.96, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    gl.useProgram(prog);
    var R = extent * 1.6 * cam.dist, cp = Math.cos(cam.pitch), c = cam.centre;
    var eye = [c[0] + R * cp * Math.cos(cam.yaw), c[1] + R * cp * Math.sin(cam.yaw), c[2] + R * Math.sin(cam.pitch)];
    var vp = mul(perspective(0.7, canvas.width / Math.max(canvas.height, 1), R * 0.01, R * 10), lookAt(eye, c));
    gl.uniformMatrix4fv(vpLoc, false, vp);
    fill(t);
    [ells, boxes, rods, heads].forEach(function (d) {
      if (!d.used) return;
      gl.bindVertexArray(d.vao);
      gl.bindBuffer(gl.ARRAY_BUFFER, d.ib);
      gl.bufferSubData(gl.ARRAY_BUFFER, 0, d.data, 0, d.used * 15);
      gl.drawArraysInstanced(gl.TRIANGLES, 0, d.n, d.used);
    });
    if (P) {
      gl.useProgram(pprog);
      gl.uniformMatrix4fv(pvpLoc, false, vp);
      gl.uniform1f(scaleLoc, canvas.height / 2 / Math.tan(0.35));
      gl.bindVertexArray(dotVao);
      gl.bindBuffer(gl.ARRAY_BUFFER, dotBuf);
      gl.bufferSubData(gl.ARRAY_BUFFER, 0, dotData, 0, P * 7);
      gl.drawArrays(gl.POINTS, 0, P);
    }
    gl.bindVertexArray(null);
    label.textContent = D.title + "   t = " + t.toFixed(D.decimals) + " s";
    drawn++;
  }
  var t0 = T[0], t1 = T[F - 1], now = t0, playing = F > 1, last = null, drawn = 0;
  function setTime(t) {
    now = Math.min(Math.max(t, t0), t1);
    slider.value = t1 > t0 ? String(Math.round(1000 * (now - t0) / (t1 - t0))) : "0";
  }
  function tick(ms) {
    if (playing && last !== null) {
      var t = now + (ms - last) / 1000 * parseFloat(speedSel.value);
      if (t > t1) t = t0 + (t - t1) % Math.max(t1 - t0, 1e-300);
      setTime(t);
    }
    last = ms;
    draw(now);
    root.dataset.frames = String(drawn);
    root.dataset.ready = "yes";
    requestAnimationFrame(tick);
  }
  button.addEventListener("click", function () {
    playing = !playing; button.textContent = playing ? "pause" : "play";
  });
  button.textContent = playing ? "pause" : "play";
  slider.addEventListener("input", function () {
    setTime(t0 + (t1 - t0) * parseInt(slider.value, 10) / 1000);
  });
  var drag = null;
  canvas.addEventListener("pointerdown", function (e) { drag = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); });
  canvas.addEventListener("pointerup", function () { drag = null; });
  canvas.addEventListener("pointermove", function (e) {
    if (!drag) return;
    cam.yaw -= (e.clientX - drag[0]) * 0.008;
    cam.pitch = Math.max(-1.55, Math.min(1.55, cam.pitch + (e.clientY - drag[1]) * 0.008));
    drag = [e.clientX, e.clientY];
  });
  canvas.addEventListener("wheel", function (e) {
    e.preventDefault();
    cam.dist = Math.max(0.05, Math.min(20, cam.dist * Math.exp(e.deltaY * 0.001)));
  }, { passive: false });
  canvas.addEventListener("dblclick", function () { cam.yaw = D.view[0]; cam.pitch = D.view[1]; cam.dist = 1; });
  setTime(t0);
  draw(now); // the first frame at once, whenever the browser starts animating
  root.dataset.ready = "yes";
  if (location.hash === "#bench") { // benchmarks/viewer.py: frames drawn per second, synchronously
    var px = new Uint8Array(4), n = 120, start = performance.now();
    for (var k = 0; k < n; k++) {
      draw(t0 + (t1 - t0) * k / n);
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px); // waits for the frame
    }
    root.dataset.benchFps = String(n / ((performance.now() - start) / 1000));
    start = performance.now();
    for (k = 0; k < n; k++) fill(t0 + (t1 - t0) * k / n); // the script's share of a frame
    root.dataset.benchFillMs = String((performance.now() - start) / n);
  }
  requestAnimationFrame(tick);
})();
