// Locus teaching UI: draws what the server sends over the WebSocket and
// sends the controls back. The simulation and the filter run on the server
// (protocol: docs/ui.md). Time series use uPlot (vendored, window.uPlot);
// the arena and the ellipses are drawn on canvases.

const $ = (id) => document.getElementById(id);
const WINDOW = 4000; // samples kept in the charts (40 s at 100 Hz)

// State the end-to-end tests read (window.locus).
const locus = {
  connected: false, hello: null, params: null, state: null, frames: 0,
  samples: 0, teleopFrames: 0, errors: [], lastCsv: null, ellipse: null,
  lastCorrection: null, charts: {}, estPoints: 0,
  // Attached to a robot (hello.robot), else null; the link's health.
  robot: null, link: null,
  // Every NIS received since the page loaded, with its time: {t, nis}.
  nisLog: [],
};
window.locus = locus;

// ---- WebSocket ------------------------------------------------------------
let ws;
function connect() {
  ws = new WebSocket(`ws://${location.host}/ws`);
  ws.onopen = () => { locus.connected = true; setConn('connected', 'ok'); };
  ws.onclose = () => { locus.connected = false; setConn('disconnected: reload the page', 'bad'); };
  ws.onmessage = (ev) => {
    let msg;
    try { msg = JSON.parse(ev.data); } catch { return; }
    const handler = handlers[msg.type];
    if (handler) handler(msg);
  };
}
function send(msg) {
  if (ws && ws.readyState === WebSocket.OPEN) ws.send(JSON.stringify(msg));
}
function setConn(text, cls) { const c = $('conn'); c.textContent = text; c.className = 'conn ' + cls; }

// ---- Series buffers ---------------------------------------------------------
const buf = {
  t: [], pxx: [], pyy: [], ptt: [], in1: [], in2: [], nis: [], gate: [], v1: [], v2: [], s1: [], s2: [],
  truth: [], est: [], odo: [],
};
const PATH_MAX = 60000;
function clearBuffers() { for (const k of Object.keys(buf)) buf[k].length = 0; }
function push(key, v, max = WINDOW) { const a = buf[key]; a.push(v); if (a.length > max) a.splice(0, a.length - max); }

// Gate threshold of chi-square with 2 dof at confidence c: -2 ln(1 - c).
function gateThreshold(c) { return c > 0 && c < 1 ? -2 * Math.log(1 - c) : null; }

// ---- Charts (uPlot) -----------------------------------------------------------
// A plot fills its container's width (the grid decides it; the plot never
// widens it): uPlot's own setSize, on every change of the container.
const chartHeight = () => (document.body.classList.contains('big') ? 200 : 150);
function chartWidth(id) { return Math.max(200, $(id).clientWidth - 2); }
// Axes before any data: a scale with nothing to show gets a placeholder
// range, so each plot shows its axes, units and legend from the start.
function placeholderRange(lo, hi, log) {
  return (u, min, max) => {
    if (min == null || max == null || !Number.isFinite(min) || !Number.isFinite(max)) return [lo, hi];
    if (log) return uPlot.rangeLog(min, max, 10, true);
    return min === max ? uPlot.rangeNum(min - 1, max + 1, 0.1, true) : uPlot.rangeNum(min, max, 0.1, true);
  };
}
const expTicks = (u, splits) => splits.map((v) => (v === null ? '' : v.toExponential(0)));
function makeChart(id, title, series, scales, axes) {
  const opts = {
    title, width: chartWidth(id), height: chartHeight(),
    scales: Object.assign({ x: { time: false, range: (u, min, max) => (min == null || max == null ? [0, 10] : min === max ? [min, min + 1] : [min, max]) } }, scales),
    series: [{ label: 't [s]' }].concat(series),
    axes: [{ label: 't [s]', size: 30 }].concat(axes),
    legend: { live: true },
    cursor: { drag: { x: false, y: false } },
  };
  const data = [[]].concat(series.map(() => []));
  const u = new uPlot(opts, data, $(id));
  locus.charts[id] = u;
  new ResizeObserver(() => {
    const width = chartWidth(id);
    if (width !== u.width || chartHeight() !== u.height) u.setSize({ width, height: chartHeight() });
  }).observe($(id));
  return u;
}
const charts = {};
function initCharts() {
  const logm = { distr: 3, auto: true, range: placeholderRange(1e-6, 1, true) };
  const lin = (lo, hi) => ({ auto: true, range: placeholderRange(lo, hi, false) });
  charts.p = makeChart('chart-p', 'Covariance: P_x, P_y [m²] (left), P_θ [rad²] (right), log',
    [{ label: 'P_x [m²]', stroke: '#0b6e99', scale: 'm2' },
     { label: 'P_y [m²]', stroke: '#9467bd', scale: 'm2' },
     { label: 'P_θ [rad²]', stroke: '#f0a202', scale: 'rad2' }],
    { m2: logm, rad2: logm },
    [{ scale: 'm2', size: 60, values: expTicks }, { scale: 'rad2', side: 1, size: 60, grid: { show: false }, values: expTicks }]);
  charts.innov = makeChart('chart-innov', 'Innovation z − h(x⁻): distance [m] (left), heading [rad] (right)',
    [{ label: 'distance [m]', stroke: '#0b6e99', scale: 'm', points: { show: true, size: 3 }, paths: () => null },
     { label: 'heading [rad]', stroke: '#d62728', scale: 'rad', points: { show: true, size: 3 }, paths: () => null }],
    { m: lin(-0.05, 0.05), rad: lin(-0.1, 0.1) }, [{ scale: 'm', size: 60 }, { scale: 'rad', side: 1, size: 60, grid: { show: false } }]);
  charts.nis = makeChart('chart-nis', 'NIS (2 dof) and the gate threshold',
    [{ label: 'NIS', stroke: '#1b2a41', points: { show: true, size: 3 }, paths: () => null },
     { label: 'gate', stroke: '#b00020', dash: [6, 4], width: 1.5 }],
    { y: { distr: 3, range: placeholderRange(0.01, 100, true) } }, [{ size: 50, values: expTicks }]);
  charts.wheels = makeChart('chart-wheels', 'Wheel speeds V1 (right), V2 (left) [m/s]',
    [{ label: 'V1 [m/s]', stroke: '#0b6e99' }, { label: 'V2 [m/s]', stroke: '#f0a202' }], { y: lin(0, 0.3) }, [{ size: 50 }]);
  charts.ir = makeChart('chart-ir', 'IR distances d_s1, d_s2 [m]',
    [{ label: 'd_s1 [m]', stroke: '#d62728' }, { label: 'd_s2 [m]', stroke: '#2ca02c' }], { y: lin(0, 0.5) }, [{ size: 50 }]);
}
function updateCharts() {
  const t = buf.t;
  charts.p.setData([t, buf.pxx, buf.pyy, buf.ptt]);
  charts.innov.setData([t, buf.in1, buf.in2]);
  charts.nis.setData([t, buf.nis, buf.gate]);
  charts.wheels.setData([t, buf.v1, buf.v2]);
  charts.ir.setData([t, buf.s1, buf.s2]);
}

// ---- Arena ------------------------------------------------------------------------
const arena = $('arena');
const actx = arena.getContext('2d');
const VIEW = 1.05; // metres from the centre to the canvas edge
const sx = (x) => (x + VIEW) / (2 * VIEW) * arena.width;
const sy = (y) => (VIEW - y) / (2 * VIEW) * arena.height;
const scale = () => arena.width / (2 * VIEW);

// The ellipse of a 2x2 covariance [[a, b], [b, c]] holding probability p:
// semi-axes k sqrt(lambda_i), k = sqrt(-2 ln(1 - p)) (2-D Gaussian).
function ellipse(a, b, c, p) {
  const k = Math.sqrt(-2 * Math.log(1 - p));
  const tr = (a + c) / 2, d = Math.sqrt(Math.max(0, ((a - c) / 2) ** 2 + b * b));
  const l1 = Math.max(0, tr + d), l2 = Math.max(0, tr - d);
  const angle = 0.5 * Math.atan2(2 * b, a - c);
  return { rx: k * Math.sqrt(l1), ry: k * Math.sqrt(l2), angle, k };
}
function ellipseProb() { return parseFloat($('ellipse-p').value); }
function ellipseMag() { return parseFloat($('ellipse-mag').value); }
function ellipseLabel() {
  const p = ellipseProb(), k = Math.sqrt(-2 * Math.log(1 - p)), m = ellipseMag();
  return `${(100 * p).toFixed(1)} % ellipse of the position (k = ${k.toFixed(2)} σ)` + (m === 1 ? ', to scale' : `, drawn ×${m}`);
}

function drawPath(ctx, pts, color, width) {
  if (pts.length < 2) return;
  ctx.strokeStyle = color; ctx.lineWidth = width; ctx.beginPath();
  ctx.moveTo(sx(pts[0][0]), sy(pts[0][1]));
  for (let i = 1; i < pts.length; i++) ctx.lineTo(sx(pts[i][0]), sy(pts[i][1]));
  ctx.stroke();
}
function drawRobot(ctx, pose, color, filled) {
  const [x, y, th] = pose, r = 0.06 * scale();
  ctx.save(); ctx.translate(sx(x), sy(y)); ctx.rotate(-th);
  ctx.beginPath(); ctx.moveTo(r, 0); ctx.lineTo(-0.7 * r, 0.6 * r); ctx.lineTo(-0.7 * r, -0.6 * r); ctx.closePath();
  ctx.lineWidth = 2; ctx.strokeStyle = color;
  if (filled) { ctx.fillStyle = color + '55'; ctx.fill(); }
  ctx.stroke(); ctx.restore();
}
function drawEllipse(ctx, cx, cy, e, pxPerM, color, fill) {
  ctx.save(); ctx.translate(cx, cy); ctx.rotate(-e.angle);
  ctx.beginPath(); ctx.ellipse(0, 0, Math.max(e.rx * pxPerM, 0.5), Math.max(e.ry * pxPerM, 0.5), 0, 0, 2 * Math.PI);
  if (fill) { ctx.fillStyle = fill; ctx.fill(); }
  ctx.strokeStyle = color; ctx.lineWidth = 2; ctx.stroke(); ctx.restore();
}

function drawArena() {
  const ctx = actx, h = locus.hello;
  ctx.clearRect(0, 0, arena.width, arena.height);
  if (!h) return;
  // The square path.
  ctx.setLineDash([6, 6]); ctx.strokeStyle = '#c9d1d9'; ctx.lineWidth = 1; ctx.beginPath();
  h.path.forEach(([x, y], i) => (i ? ctx.lineTo(sx(x), sy(y)) : ctx.moveTo(sx(x), sy(y))));
  ctx.closePath(); ctx.stroke(); ctx.setLineDash([]);
  // Walls.
  ctx.strokeStyle = '#1b2a41'; ctx.lineWidth = 4;
  for (const [[ax, ay], [bx, by]] of h.walls) { ctx.beginPath(); ctx.moveTo(sx(ax), sy(ay)); ctx.lineTo(sx(bx), sy(by)); ctx.stroke(); }
  if ($('show-odo').checked) drawPath(ctx, buf.odo, '#9aa7b4', 1.5);
  if (buf.truth.length) drawPath(ctx, buf.truth, '#1b7f3a', 2);
  drawPath(ctx, buf.est, '#0b6e99', 2);
  locus.estPoints = buf.est.length;
  const s = locus.state, last = locus.lastSample;
  if (!last) return;
  // Beams.
  for (const b of (s && s.beams) || []) {
    ctx.strokeStyle = b.hit ? '#d62728' : '#d6272855'; ctx.lineWidth = 1.5;
    ctx.setLineDash(b.hit ? [] : [3, 3]);
    ctx.beginPath(); ctx.moveTo(sx(b.from[0]), sy(b.from[1])); ctx.lineTo(sx(b.to[0]), sy(b.to[1])); ctx.stroke();
    ctx.setLineDash([]);
    if (b.hit) { ctx.fillStyle = '#d62728'; ctx.beginPath(); ctx.arc(sx(b.to[0]), sy(b.to[1]), 3, 0, 2 * Math.PI); ctx.fill(); }
  }
  if (last.truth) drawRobot(ctx, last.truth, '#1b7f3a', true);
  drawRobot(ctx, last.ekf, '#0b6e99', false);
  const e = ellipse(last.p[0], last.p[3], last.p[1], ellipseProb());
  const mag = ellipseMag();
  drawEllipse(ctx, sx(last.ekf[0]), sy(last.ekf[1]), e, scale() * mag, '#f0a202', '#f0a20233');
  locus.ellipse = { rx_m: e.rx, ry_m: e.ry, angle: e.angle, k: e.k, p: ellipseProb(), mag, rx_px: e.rx * scale() * mag, ry_px: e.ry * scale() * mag };
  ctx.font = '12px system-ui';
  ctx.fillStyle = '#ffffffd0'; ctx.fillRect(6, 4, ctx.measureText(ellipseLabel()).width + 8, 16);
  ctx.fillStyle = '#1b2a41';
  ctx.fillText(ellipseLabel(), 10, 16);
  if (s && s.teleop) { ctx.fillStyle = '#b00020'; ctx.fillText('keyboard driving', 10, 32); }
}

// ---- Step-through view of one correction ----------------------------------------
const fmt = (v) => (v === null || v === undefined ? '—' : Math.abs(v) >= 1e4 || (Math.abs(v) < 1e-3 && v !== 0) ? v.toExponential(3) : v.toFixed(4));
const vec = (v) => '[' + v.map(fmt).join(', ') + ']';
const mat = (m) => m.map((r) => '[' + r.map(fmt).join(', ') + ']').join('\n');
function showCorrection(d) {
  locus.lastCorrection = d;
  const gate = d.gate_threshold === null ? 'no gate: always applied' : `NIS ${fmt(d.nis)} ${d.nis <= d.gate_threshold ? '≤' : '>'} threshold ${fmt(d.gate_threshold)}`;
  const rows = [
    ['1. prediction', `x before = ${vec(d.x_before_predict)}\nu = [d1, d2] = ${vec(d.u)} m\nx⁻ = f(x, u) = ${vec(d.x_prior)}`],
    ['P⁻ = F P Fᵀ + G Q Gᵀ', mat(d.p_prior)],
    ['2. measurement', `z = [d, θ_m] = ${vec(d.z)}\nh(x⁻) = ${vec(d.h)}`],
    ['H = ∂h/∂x (2×3)', mat(d.jacobian)],
    ['V R Vᵀ', mat(d.noise)],
    ['S = H P⁻ Hᵀ + V R Vᵀ', mat(d.s)],
    ['K = P⁻ Hᵀ S⁻¹ (3×2)', mat(d.k)],
    ['3. innovation y = z − h(x⁻)', vec(d.innovation)],
    ['4. gate', `${gate} → <span class="${d.applied ? 'accept' : 'reject'}">${d.applied ? 'ACCEPTED' : 'REJECTED'}</span>`],
    ['5. x⁺ = x⁻ + K y', vec(d.x_post)],
    ['P⁺ (Joseph form)<br>= (I−KH) P⁻ (I−KH)ᵀ<br>&nbsp;&nbsp;+ K V R Vᵀ Kᵀ', mat(d.p_post)],
  ];
  $('detail').innerHTML = '<table>' + rows.map(([k, v]) => `<tr><td>${k}</td><td class="m">${v}</td></tr>`).join('') + '</table>';
  drawDetail(d);
}
function drawDetail(d) {
  const c = $('detail-canvas'), ctx = c.getContext('2d');
  ctx.clearRect(0, 0, c.width, c.height);
  const p = ellipseProb();
  const before = ellipse(d.p_prior[0][0], d.p_prior[0][1], d.p_prior[1][1], p);
  const after = ellipse(d.p_post[0][0], d.p_post[0][1], d.p_post[1][1], p);
  const cx = d.x_prior[0], cy = d.x_prior[1];
  const extent = Math.max(before.rx, after.rx, Math.hypot(d.x_post[0] - cx, d.x_post[1] - cy), 1e-6) * 1.3;
  const pxPerM = Math.min(c.width, c.height) / 2 / extent;
  const X = (x) => c.width / 2 + (x - cx) * pxPerM, Y = (y) => c.height / 2 - (y - cy) * pxPerM;
  drawEllipse(ctx, X(cx), Y(cy), before, pxPerM, '#f0a202', '#f0a20222');
  drawEllipse(ctx, X(d.x_post[0]), Y(d.x_post[1]), after, pxPerM, '#0b6e99', '#0b6e9922');
  ctx.strokeStyle = '#1b2a41'; ctx.lineWidth = 1; ctx.beginPath(); ctx.moveTo(X(cx), Y(cy)); ctx.lineTo(X(d.x_post[0]), Y(d.x_post[1])); ctx.stroke();
  ctx.fillStyle = '#1b2a41'; ctx.font = '11px system-ui';
  ctx.fillText(`${(100 * p).toFixed(1)} % ellipses, scale bar:`, 6, 14);
  const bar = niceBar(extent / 2);
  ctx.fillRect(150, 10, bar * pxPerM, 3); ctx.fillText(bar >= 0.01 ? `${(bar * 100).toPrecision(2)} cm` : `${(bar * 1000).toPrecision(2)} mm`, 154 + bar * pxPerM, 14);
  ctx.fillStyle = '#f0a202'; ctx.fillText('before (x⁻, P⁻)', 6, c.height - 20);
  ctx.fillStyle = '#0b6e99'; ctx.fillText('after (x⁺, P⁺)', 6, c.height - 6);
}
function niceBar(v) { const e = Math.pow(10, Math.floor(Math.log10(v))); return [1, 2, 5].map((m) => m * e).filter((b) => b <= v).pop() || e; }

// ---- Panel -------------------------------------------------------------------------
const LIVE = [
  ['q11', 'Q11 var(e_d) [m²/step]'], ['q22', 'Q22 var(e_dθ) [rad²/step]'],
  ['r11', 'R11 var(e_ds1) [m²]'], ['r22', 'R22 var(e_ds2) [m²]'],
  ['ir_sigma', 'injected IR noise σ [m]'], ['gate', 'gate confidence (0 = none)'],
  ['v_ref', 'V_ref [m/s]'], ['w_ref', 'W_ref [rad/s]'],
  ['k_cross', 'k_cross [rad/m]'], ['k_heading', 'k_heading [1/s]'], ['k_pos', 'k_pos [1/s]'],
];
const INITIAL = [
  ['start_x', 'x₀ [m]'], ['start_y', 'y₀ [m]'], ['start_theta', 'θ₀ [rad]'],
  ['std_x', 'σ_x₀ [m]'], ['std_y', 'σ_y₀ [m]'], ['std_theta', 'σ_θ₀ [rad]'],
];
function buildForm(formId, fields) {
  const form = $(formId);
  for (const [f, label] of fields) {
    form.insertAdjacentHTML('beforeend',
      `<label for="p-${f}">${label}</label><div class="cell"><input id="p-${f}" class="num" data-field="${f}">` +
      `<span class="inuse" id="inuse-${f}"></span><span class="err" id="err-${f}" hidden></span></div>`);
  }
  const ir = form.querySelector('#p-ir_sigma');
  if (ir) { ir.parentElement.classList.add('sim-only'); form.querySelector('label[for="p-ir_sigma"]').classList.add('sim-only'); }
  if (formId === 'params') {
    form.insertAdjacentHTML('beforeend', '<label for="p-use_ir">filter uses the IR</label><div class="cell"><input type="checkbox" id="p-use_ir"><span class="err" id="err-use_ir" hidden></span></div>');
  }
  form.addEventListener('submit', (e) => e.preventDefault());
}
function clearErrors() {
  document.querySelectorAll('.err').forEach((e) => { e.hidden = true; e.textContent = ''; });
  document.querySelectorAll('input.invalid').forEach((e) => e.classList.remove('invalid'));
  $('errors').hidden = true;
}
function collect(fields) {
  const values = {};
  for (const [f] of fields) values[f] = $('p-' + f).value;
  return values;
}
function showError(field, message) {
  locus.errors.push({ field, message });
  const banner = $('errors');
  banner.textContent = `${field}: ${message} (nothing was applied; the run keeps its last good values)`;
  banner.hidden = false;
  const span = $('err-' + field), input = $('p-' + field) || (field === 'speed' ? $('speed') : null);
  if (span) { span.textContent = message; span.hidden = false; }
  if (input) input.classList.add('invalid');
}

// ---- Messages from the server ----------------------------------------------------------
const handlers = {
  hello(m) {
    locus.hello = m;
    document.title = `Locus teaching UI: ${m.scenario} (session ${m.session})`;
    const sel = $('scenario');
    sel.innerHTML = m.scenarios.map((s) => `<option ${s === m.scenario ? 'selected' : ''}>${s}</option>`).join('');
    $('presets').innerHTML = m.presets.map((p) => `<button id="preset-${p.step}" title="${p.setup}: ${p.demonstrates}">${p.step})</button>`).join('');
    for (const p of m.presets) $('preset-' + p.step).onclick = () => { clearErrors(); send({ type: 'preset', step: p.step }); };
    for (const l of m.limits) {
      const el = $('p-' + l.field);
      if (el) el.title = `${l.min} … ${l.max} ${l.unit}`;
    }
    locus.robot = m.robot || null;
    document.body.classList.toggle('robot', !!m.robot);
    $('robot-panel').hidden = !m.robot;
    if (m.robot) {
      document.title = `Locus: attached to the robot (${m.robot.link})`;
      $('robot-link').textContent = m.robot.link;
      // What a live robot cannot do is off (docs/ui.md).
      for (const id of ['step', 'reset', 'export', 'speed', 'apply-initial', 'scenario']) $(id).disabled = true;
      // The robot runs on: the button shows the host's next correction.
      $('step-correction').title = 'Show the next IR correction the host makes (the robot keeps moving: press stop first to hold it still)';
      $('detail').textContent = 'Press “Next correction” to see the next correction the host makes on the robot’s packets: prediction, H, S, K, innovation, gate, ellipse before and after. The robot keeps moving (stop it first to hold it still).';
      document.querySelector('footer').textContent = 'The filter (locus-core\'s EKF) runs in the host on the server, on the packets of the robot over the link; this page draws what it sends. Charts: uPlot.';
    }
    clearBuffers(); drawArena();
  },
  params(m) {
    locus.params = m;
    const v = m.values;
    for (const [f] of LIVE.concat(INITIAL)) {
      if (v[f] === null || v[f] === undefined) continue; // not for a robot
      const input = $('p-' + f);
      $('inuse-' + f).textContent = 'in use: ' + v[f];
      if (!input.classList.contains('invalid') && document.activeElement !== input) input.value = v[f];
    }
    $('p-use_ir').checked = v.use_ir;
    if (v.speed !== null && !$('speed').classList.contains('invalid') && document.activeElement !== $('speed')) $('speed').value = v.speed;
    document.querySelectorAll('#presets button').forEach((b) => b.classList.toggle('active', b.id === 'preset-' + m.preset));
    if (!m.preset) $('figure').textContent = 'No guide step loaded (values set by hand).';
    else {
      const p = locus.hello.presets.find((q) => q.step === m.preset);
      $('figure').innerHTML = `<b>Step ${p.step})</b> ${p.setup}<br><i>${p.demonstrates}</i><br>criterion: ${p.criterion}<br>live: <span id="figure-live">—</span>`;
    }
  },
  state(m) {
    const prev = locus.state;
    if (prev && m.steps < prev.steps) clearBuffers();
    if (m.steps === 0) clearBuffers();
    locus.state = m; locus.frames++;
    if (m.teleop) locus.teleopFrames++;
    const gate = locus.params ? gateThreshold(locus.params.values.gate) : null;
    for (const s of m.samples) {
      push('t', s.t); push('pxx', s.p[0]); push('pyy', s.p[1]); push('ptt', s.p[2]);
      push('in1', s.innovation ? s.innovation[0] : null); push('in2', s.innovation ? s.innovation[1] : null);
      push('nis', s.nis); push('gate', gate);
      push('v1', s.wheels[0]); push('v2', s.wheels[1]);
      push('s1', s.ir ? s.ir[0] : null); push('s2', s.ir ? s.ir[1] : null);
      if (s.truth) push('truth', s.truth, PATH_MAX);
      push('est', s.ekf, PATH_MAX);
      if (s.odo) push('odo', s.odo, PATH_MAX);
      locus.lastSample = s; locus.samples++;
      if (s.nis !== null) { locus.nisLog.push({ t: s.t, nis: s.nis }); if (locus.nisLog.length > 20000) locus.nisLog.shift(); }
    }
    if (m.correction) showCorrection(m.correction);
    if (m.figure && $('figure-live')) {
      const f = m.figure, cls = f.ok === null ? 'wait' : f.ok ? 'ok' : 'fail';
      $('figure-live').innerHTML = `${f.measured} <span class="verdict ${cls}">${f.ok === null ? '(pending)' : f.ok ? '✓ meets it' : '✗ not met'}</span>`;
    }
    if (m.link) showLink(m);
    else {
      const mode = m.failure ? `FAILED: ${m.failure}` : m.finished ? 'finished' : m.running ? 'running' : 'paused';
      $('status').textContent = `${mode} · t = ${m.time.toFixed(2)} s · step ${m.steps} · laps ${m.laps}` + (m.teleop ? ' · keyboard' : '');
    }
    scheduleDraw();
  },
  error(m) { showError(m.field, m.message); },
  csv(m) {
    locus.lastCsv = { filename: m.filename, rows: m.csv.split('\n').length - 2, truncated: m.truncated };
    if (m.truncated) showError('export', 'the log was cut at its size limit: the file holds the first 30 000 steps');
    const blob = new Blob([m.csv], { type: 'text/csv' });
    const a = document.createElement('a');
    a.href = URL.createObjectURL(blob); a.download = m.filename;
    document.body.appendChild(a); a.click(); a.remove();
    setTimeout(() => URL.revokeObjectURL(a.href), 10000);
  },
};

// The link's health while attached to a robot: the host's counters,
// latency and clock (docs/protocol.md defines each counter).
const LINK_ROWS = [
  ['applied', 'packets applied'], ['lost', 'lost'], ['duplicate', 'duplicate'], ['late', 'late'],
  ['corrupt', 'corrupt (CRC)'], ['malformed', 'malformed'], ['suspect', 'suspect (sequence)'],
  ['implausible', 'implausible (content)'], ['resync', 'resynchronisations'],
  ['frames_malformed', 'serial frames dropped: malformed'], ['frames_oversize', 'serial frames dropped: oversize'],
  ['filter_errors', 'filter errors (belief kept)'], ['corrections', 'IR corrections applied'], ['commands_sent', 'commands sent'],
];
function showLink(m) {
  const l = m.link;
  locus.link = l;
  const us = (v) => (v === null ? '—' : `${v.toFixed(1)} µs`);
  const rows = LINK_ROWS.map(([k, label]) => [label, `<span id="link-${k}">${l[k]}</span>`]);
  rows.push(['receive → command latency, median / max (last 1000)', `<span id="link-latency">${us(l.latency_p50_us)} / ${us(l.latency_max_us)}</span>`]);
  rows.push(['robot clock offset / drift', `<span id="link-clock">${l.clock_offset_s === null ? '—' : `${l.clock_offset_s.toFixed(6)} s / ${l.clock_drift_ppm.toFixed(1)} ppm`}</span>`]);
  $('link-table').innerHTML = rows.map(([k, v]) => `<tr><td>${k}</td><td class="m">${v}</td></tr>`).join('');
  const last = locus.nisLog.slice(-50);
  $('nis-mean').textContent = last.length ? (last.reduce((a, e) => a + e.nis, 0) / last.length).toPrecision(3) : '—';
  const drive = { path: 'path controller driving', stopped: 'stopped (zero wheel speeds)', keyboard: 'keyboard driving' }[l.drive];
  const mode = m.failure ? `FAILED: ${m.failure}` : l.silent ? 'waiting for the robot (sending hellos)' : drive;
  $('status').textContent = `${mode} · robot time ${m.time.toFixed(2)} s · packets applied ${m.steps} · no ground truth`;
}

let drawPending = false;
function scheduleDraw() {
  if (drawPending) return;
  drawPending = true;
  requestAnimationFrame(() => { drawPending = false; updateCharts(); drawArena(); });
}

// ---- Controls ------------------------------------------------------------------------
function wire() {
  $('start').onclick = () => send({ type: 'start' });
  $('stop').onclick = () => send({ type: 'stop' });
  $('step').onclick = () => send({ type: 'step' });
  $('step-correction').onclick = () => send({ type: 'step_correction' });
  $('reset').onclick = () => { clearErrors(); send({ type: 'reset' }); };
  $('export').onclick = () => send({ type: 'export' });
  $('speed').onchange = () => { clearErrors(); send({ type: 'speed', factor: $('speed').value }); };
  $('apply-params').onclick = () => {
    clearErrors();
    const values = collect(LIVE); values.use_ir = $('p-use_ir').checked;
    if (locus.robot) delete values.ir_sigma; // the robot's IR noise is its own
    send({ type: 'params', values });
  };
  $('apply-initial').onclick = () => { clearErrors(); send({ type: 'initial', values: collect(INITIAL) }); send({ type: 'reset' }); };
  $('scenario').onchange = () => { clearErrors(); send({ type: 'scenario', name: $('scenario').value }); };
  for (const id of ['ellipse-p', 'ellipse-mag', 'show-odo']) $(id).onchange = () => { scheduleDraw(); if (locus.lastCorrection) drawDetail(locus.lastCorrection); };
  $('ellipse-label').textContent = 'covariance ellipse';

  // Keyboard teleoperation: arrows, repeated while held (the server stops
  // 0.5 s after the last repeat).
  const held = new Set();
  const KEYS = ['ArrowUp', 'ArrowDown', 'ArrowLeft', 'ArrowRight'];
  const command = () => {
    // The server's limit of teleop_v (hello's limits), not a copy of it.
    const top = locus.hello ? locus.hello.limits.find((l) => l.field === 'teleop_v') : null;
    const vref = Math.min(locus.params ? locus.params.values.v_ref : 0.1, top ? top.max : 0);
    const v = (held.has('ArrowUp') ? vref : 0) - (held.has('ArrowDown') ? vref : 0);
    const w = (held.has('ArrowLeft') ? 1 : 0) - (held.has('ArrowRight') ? 1 : 0);
    return { type: 'teleop', v, w };
  };
  let repeat = null;
  document.addEventListener('keydown', (e) => {
    if (!KEYS.includes(e.key) || e.target.tagName === 'INPUT' || e.target.tagName === 'SELECT') return;
    e.preventDefault();
    held.add(e.key);
    send(command());
    if (!repeat) repeat = setInterval(() => send(command()), 150);
  });
  document.addEventListener('keyup', (e) => {
    if (!KEYS.includes(e.key)) return;
    held.delete(e.key);
    if (held.size === 0) { clearInterval(repeat); repeat = null; send({ type: 'teleop_off' }); } else send(command());
  });
  $('big').onclick = () => {
    const on = document.body.classList.toggle('big');
    $('big').setAttribute('aria-pressed', String(on));
    $('big').classList.toggle('active', on);
    for (const [id, u] of Object.entries(locus.charts)) u.setSize({ width: chartWidth(id), height: chartHeight() });
  };
}

buildForm('params', LIVE);
buildForm('initial', INITIAL);
initCharts();
wire();
connect();
