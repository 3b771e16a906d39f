// The rths view: reads /api/stream (server-sent events, each a JSON of what is new: header once,
// samples, spectra, events, status) and draws it with uPlot. Live: the last WINDOW_S seconds.
// Replay (a finished record): a time slider; every chart shows the record up to the slider.
// Units: displacement mm, force N, lag and lateness ms, time s, frequency Hz (log axis), TI mm^2.
// The response (per floor or DOF) is drawn against the in-process prediction when the view was
// given one (null where there is none), with their running difference.
'use strict';
const WINDOW_S = 10;
const COLORS = ['#1f5fbf', '#d1451b', '#2a8f2a', '#8e44ad'];
const V = window.rthsView = {
  header: null, context: null, cols: null, spectra: [], events: [], status: null,
  mode: 'live', plots: {}, updates: 0, holdSeenMs: null, health: null,
};
const $ = id => document.getElementById(id);

function chartWidth() { return Math.max(300, Math.floor((window.innerWidth - 60) / 3)); }

// dashes[i]: the dash pattern of series i (px), or undefined for a solid line; yRange: uPlot's
// y range function, or undefined for its default.
function timePlot(el, title, yLabel, names, colors, dashes = [], yRange = undefined) {
  const series = [{ label: 'time (s)' }], scales = { x: { time: false } };
  names.forEach((n, i) => series.push({ label: n, stroke: colors[i % colors.length],
    width: dashes[i] ? 2 : 1.5, dash: dashes[i] }));
  if (yRange) scales.y = { range: yRange };
  return new uPlot({
    title, width: chartWidth(), height: 210, class: 'chart', scales,
    series, legend: { live: false },
    axes: [{ label: 'time (s)' }, { label: yLabel, size: 60 }],
  }, [[], ...names.map(() => [])], el);
}

function xyPlot(el, title, xLabel, yLabel, color) {
  return new uPlot({
    mode: 2, title, width: chartWidth(), height: 210, class: 'chart',
    scales: { x: { time: false, auto: true }, y: { auto: true } },
    legend: { show: false },
    series: [{}, { stroke: color, width: 1.2, paths: uPlot.paths.linear(), points: { show: false },
                   facets: [{ scale: 'x', auto: true }, { scale: 'y', auto: true }] }],
    axes: [{ label: xLabel }, { label: yLabel, size: 60 }],
  }, [null, [[], []]], el);
}

// Amplitude (mm) against frequency on a log axis (Hz): decades 1, 10, 100 labelled.
function spectrumPlot(el, title, color) {
  return new uPlot({
    title, width: chartWidth(), height: 210, class: 'chart',
    scales: { x: { time: false, distr: 3, log: 10 } },
    series: [{ label: 'frequency (Hz)' }, { label: 'amplitude (mm)', stroke: color, width: 1.5 }],
    legend: { live: false },
    axes: [{ label: 'frequency (Hz, log scale)',
             values: (u, splits) => splits.map(v => [0.1, 1, 10, 100, 1000].includes(Math.round(v * 1e6) / 1e6) ? String(v) : '') },
           { label: 'error amplitude (mm)', size: 60 }],
  }, [[], []], el);
}

function row(parent, heading) {
  const h = document.createElement('h2'); h.textContent = heading; parent.appendChild(h);
  const r = document.createElement('div'); r.className = 'row'; parent.appendChild(r);
  return r;
}

function linkLabel(id) {
  const kind = (V.header.link_labels || {})[String(id)] || ((V.context || {}).node_kinds || {})[String(id)];
  return 'node ' + id + (kind ? ' (' + kind.toLowerCase().replace(/_/g, ' ') + ')' : '');
}

// Symmetric about 0, at least ±0.001 mm: a difference of 0 reads as 0, not on a 0-100 axis.
function symmetricRange(u, min, max) {
  const m = 1.1 * Math.max(Math.abs(min || 0), Math.abs(max || 0), 0.001);
  return [-m, m];
}

function dofLabel(d) { return (V.header.dof_labels || [])[d] || 'DOF ' + (d + 1); }

// Per floor (DOF): measured and predicted displacement; one chart of their difference.
function buildResponse() {
  const h = V.header, el = $('response'), pred = (V.context && V.context.prediction) || {};
  el.innerHTML = ''; V.plots.resp = [];
  $('prediction-text').textContent = pred.text || 'no in-process prediction';
  for (let d = 0; d < h.dofs; d++)
    V.plots.resp.push(timePlot(el, dofLabel(d) + ': measured vs in-process prediction', 'displacement (mm)',
      ['measured (mm)', 'predicted (mm)'], ['#d1451b', '#1f5fbf'], [undefined, [7, 5]]));
  V.plots.diff = timePlot(el, 'measured − predicted displacement', 'difference (mm)',
    Array.from({ length: h.dofs }, (_, d) => dofLabel(d) + ' (mm)'), COLORS, [], symmetricRange);
}

function buildCharts() {
  const h = V.header, acts = $('actuators'), links = $('links');
  acts.innerHTML = ''; links.innerHTML = ''; V.plots = { act: [], link: [] };
  buildResponse();
  for (let a = 0; a < h.actuators; a++) {
    const r = row(acts, 'Actuator ' + (a + 1));
    const c = COLORS[a % COLORS.length];
    V.plots.act.push({
      cmd: timePlot(r, 'command vs measured displacement', 'displacement (mm)', ['command (mm)', 'measured (mm)'], ['#1f5fbf', '#d1451b']),
      err: timePlot(r, 'tracking error (command − measured)', 'error (mm)', ['error (mm)'], [c]),
      spec: spectrumPlot(r, 'tracking error spectrum (last ' + h.spectrum_window_s.toFixed(2) + ' s, Hann)', c),
      sync: xyPlot(r, 'synchronisation: measured vs command', 'command (mm)', 'measured (mm)', c),
      ti: timePlot(r, 'tracking indicator (grows when the actuator lags)', 'TI (mm²)', ['TI (mm²)'], [c]),
      hyst: xyPlot(r, 'force vs measured displacement', 'measured displacement (mm)', 'force (N)', c),
    });
  }
  h.links.forEach((id, l) => V.plots.link.push(timePlot(links, 'lag, ' + linkLabel(id),
    'lag (ms)', ['injected (ms)', 'measured round trip (ms)'], ['#2a8f2a', '#d1451b'])));
  V.plots.deadlines = timePlot(links, 'overruns and late feedback so far', 'steps (count)',
    ['overruns (count)', 'late feedback (count)'], ['#c0221b', '#8e44ad']);
  V.plots.lateness = timePlot(links, 'lateness of each step (> 0 = overrun)', 'lateness (ms)', ['lateness (ms)'], ['#555']);
}

function reset(header, context) {
  V.header = header; V.context = context; V.spectra = []; V.events = [];
  V.cols = { step: [], time_s: [], lateness_ms: [], overruns: [], late_feedback: [] };
  for (const k of ['u_mm', 'predicted_u_mm', 'difference_mm'])
    V.cols[k] = Array.from({ length: header.dofs }, () => []);
  for (const k of ['command_mm', 'measured_mm', 'error_mm', 'force_N', 'ti_mm2'])
    V.cols[k] = Array.from({ length: header.actuators }, () => []);
  for (const k of ['injected_ms', 'round_trip_ms'])
    V.cols[k] = Array.from({ length: header.links.length }, () => []);
  $('run').textContent = header.study + ' · case ' + header.case + ' · ' + header.clock.replace('_', ' ') +
    ' · dt ' + (header.dt_s * 1e3) + ' ms · run ' + header.run_id;
  const cd = (context && context.critical_delay) || {};
  $('critical').textContent = cd.margin_pct !== undefined
    ? cd.critical_delay_ms.toFixed(2) + ' ms, margin ' + cd.margin_pct.toFixed(0) + ' %' : (cd.text || '–');
  $('critical').title = cd.text || '';
  if (context && context.note) $('run').textContent += ' · ' + context.note;
  buildCharts();
}

function append(dst, src) { for (let i = 0; i < src.length; i++) dst.push(src[i]); }

function merge(u) {
  if (u.header) reset(u.header, u.context);
  if (!V.cols) return;
  const s = u.samples;
  if (s) for (const k of Object.keys(V.cols)) {
    if (!s[k]) continue;
    if (Array.isArray(V.cols[k][0]) || (V.cols[k].length && Array.isArray(s[k][0])))
      s[k].forEach((col, i) => append(V.cols[k][i], col));
    else append(V.cols[k], s[k]);
  }
  if (u.spectra) append(V.spectra, u.spectra);
  if (u.events) append(V.events, u.events);
}

// Index range [i0, i1) of the samples drawn: live, the last WINDOW_S s; replay, up to the slider.
function visible(windowed) {
  const t = V.cols.time_s, n = t.length;
  let end = n;
  if (V.mode === 'replay') { const tmax = +$('slider').value; end = 0; while (end < n && t[end] <= tmax + 1e-12) end++; }
  if (!windowed && V.mode === 'replay') return [0, end];
  const from = end ? t[end - 1] - WINDOW_S : 0;
  let i0 = end; while (i0 > 0 && t[i0 - 1] >= from) i0--;
  return [i0, end];
}

function drawActuator(a, p, i0, i1) {
  const c = V.cols, t = c.time_s.slice(i0, i1);
  const cmd = c.command_mm[a].slice(i0, i1), meas = c.measured_mm[a].slice(i0, i1);
  p.cmd.setData([t, cmd, meas]);
  p.err.setData([t, c.error_mm[a].slice(i0, i1)]);
  p.ti.setData([t, c.ti_mm2[a].slice(i0, i1)]);
  const [x0, x1] = visible(true);
  p.sync.setData([null, [c.command_mm[a].slice(x0, x1), c.measured_mm[a].slice(x0, x1)]]);
  p.hyst.setData([null, [c.measured_mm[a].slice(x0, x1), c.force_N[a].slice(x0, x1)]]);
  const tEnd = i1 ? c.time_s[i1 - 1] : 0;
  let spec = null;
  for (const s of V.spectra) if (s.time_s <= tEnd + 1e-12) spec = s;
  p.spec.setData(spec ? [V.header.spectrum_hz, spec.amplitude_mm[a]] : [[], []]);
  p.specStep = spec ? spec.step : null;
}

function drawResponse(i0, i1) {
  const c = V.cols, t = c.time_s.slice(i0, i1);
  V.plots.resp.forEach((p, d) => p.setData([t, c.u_mm[d].slice(i0, i1), c.predicted_u_mm[d].slice(i0, i1)]));
  V.plots.diff.setData([t, ...c.difference_mm.map(col => col.slice(i0, i1))]);
}

// Max and RMS of measured − predicted so far, per floor (the feed's, over the samples compared).
function showPrediction(st) {
  const p = st.prediction;
  if (!p) { $('prediction-stats').textContent = ''; return; }
  $('prediction-stats').textContent = p.max_abs_difference_mm.map((m, d) => dofLabel(d) + ': max |measured − predicted| ' +
    (m === 0 ? '0 mm (identical)' : m.toFixed(3) + ' mm, rms ' + p.rms_difference_mm[d].toFixed(3) + ' mm')).join(' · ') +
    ' (over ' + p.compared_samples + ' samples)';
}

function draw() {
  V.drawPending = false;
  if (!V.cols) return;
  const [i0, i1] = visible(false), c = V.cols, t = c.time_s.slice(i0, i1);
  V.plots.act.forEach((p, a) => drawActuator(a, p, i0, i1));
  drawResponse(i0, i1);
  V.plots.link.forEach((p, l) => p.setData([t, c.injected_ms[l].slice(i0, i1), c.round_trip_ms[l].slice(i0, i1)]));
  V.plots.deadlines.setData([t, c.overruns.slice(i0, i1), c.late_feedback.slice(i0, i1)]);
  V.plots.lateness.setData([t, c.lateness_ms.slice(i0, i1)]);
  V.drawn = { i0, i1, steps: c.step.slice(i0, i1) };
}

function showStatus(st) {
  V.status = st;
  // A HOLD stays on the badge after the run stopped: the footer often follows it within an update.
  const held = st.state === 'HOLD' || V.events.some(e => e.what.startsWith('HOLD'));
  const state = $('state');
  state.textContent = held && st.state !== 'HOLD' ? 'HOLD · ' + st.state : st.state;
  state.className = 'state ' + (held ? 'HOLD' : st.state);
  if (held && V.holdSeenMs === null) V.holdSeenMs = Date.now();
  $('step').textContent = st.latest_step < 0 ? '–' : st.latest_step;
  $('time').textContent = st.latest_time_s.toFixed(3);
  $('overruns').textContent = st.overruns;
  $('late').textContent = st.late_feedback;
  $('reason').textContent = st.state === 'completed' ? '' : (st.reason ? st.reason : '') + (st.node ? ' [' + st.node + ']' : '');
  if (V.header) showPrediction(st);
  const behind = $('behind');
  if (V.mode === 'replay') { $('behind-box').hidden = true; return; }
  if (st.finished) { behind.textContent = 'run over'; return; }
  if (st.latest_step_realtime_ns > 0) {
    const ms = Date.now() - st.latest_step_realtime_ns / 1e6;
    behind.textContent = ms.toFixed(0) + ' ms';
    $('behind-box').className = ms > 500 ? 'late' : '';
  }
}

function showEvents() {
  const ol = $('events'); ol.innerHTML = '';
  for (const e of V.events.slice(-200).reverse()) {
    const li = document.createElement('li');
    li.textContent = 'step ' + e.step + ': ' + e.what; ol.appendChild(li);
  }
}

function setupReplay() {
  const slider = $('slider'), t = V.cols ? V.cols.time_s : [];
  const end = t.length ? t[t.length - 1] : 0;
  $('replay').hidden = false; slider.max = end; slider.value = end;
  $('slider-end').textContent = end.toFixed(3); $('slider-time').textContent = end.toFixed(3);
  slider.oninput = () => { $('slider-time').textContent = (+slider.value).toFixed(3); draw(); };
}

function onUpdate(u) {
  V.updates++; V.mode = u.mode || V.mode;
  merge(u);
  showStatus(u.status);
  if (u.events && u.events.length) showEvents();
  if (u.status.finished && V.source) { V.source.close(); V.source = null; if (V.mode === 'replay') setupReplay(); }
  if (!V.drawPending) { V.drawPending = true; requestAnimationFrame(draw); }
}

function connect() {
  const es = V.source = new EventSource('/api/stream');
  es.onmessage = m => onUpdate(JSON.parse(m.data));
  es.onerror = () => {
    es.close(); V.source = null;
    if (V.status && V.status.finished) return;
    $('reason').textContent = 'connection to the view lost (the coordinator has exited?); retrying';
    setTimeout(connect, 1000);
  };
}

async function setupStop() {
  V.health = await (await fetch('/api/health')).json();
  if (!V.health.stop_enabled) return;
  $('stop-box').hidden = false;
  $('token').hidden = !V.health.token_required;
  $('stop').onclick = async () => {
    if (!confirm('Stop the test? The actuators HOLD, then every node STOPs.')) return;
    const r = await fetch('/api/stop', { method: 'POST', headers: { 'X-RTHS-Token': $('token').value } });
    $('reason').textContent = await r.text();
    if (r.ok) $('stop').disabled = true;
  };
}

setupStop();
connect();
