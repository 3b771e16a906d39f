// The rths view: reads /api/stream (server-sent events, each a JSON of what is new: header once,
// samples, spectra, events, status) and draws it with uPlot. Live: the last WINDOW_S seconds.
// Replay (a finished record, or a live run once it has finished): a time slider; every chart
// shows the run up to the slider.
// Units: displacement mm, force N, lag and lateness ms, time s, frequency Hz (log axis), TI mm^2.
// The response (per floor or DOF) is drawn against the in-process prediction when the view was
// given one (null where there is none), with their running difference.
// Drawing: updates merge at the server's rate; the charts are redrawn at most FPS times a second
// while live (URL parameter ?fps=N, 1-60, default 10), not at all while the page is hidden, only
// the charts whose data changed, and with at most about one sample per pixel of a chart's width
// (every k-th whole sample of the window, see picks()). The status line
// (step, how far behind: from the newest update, at the time it is written) is written at each
// draw, and at once when the run's state changes.
'use strict';
const WINDOW_S = 10;
const FPS = fpsParameter();
const COLORS = ['#1f5fbf', '#d1451b', '#2a8f2a', '#8e44ad'];
const V = window.rthsView = {
  header: null, context: null, cols: null, spectra: [], events: [], status: null,
  mode: 'live', plots: {}, updates: 0, holdSeenMs: null, health: null,
  fps: FPS, draws: 0, lastDrawMs: -1e9, drawnKey: null,
};
const $ = id => document.getElementById(id);

// ?fps=N: draws per second while live, an integer 1-60; anything else keeps the default 10.
function fpsParameter() {
  const n = Number(new URLSearchParams(location.search).get('fps'));
  return Number.isInteger(n) && n >= 1 && n <= 60 ? n : 10;
}

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

// Amplitude (mm) against frequency on a log axis (Hz): decades 1, 10, 100 labelled. Until its
// first spectrum it says when that comes (`note`: the chart's .note element).
function spectrumPlot(el, title, color, waitS) {
  const u = new uPlot({
    title, width: chartWidth(), height: 210, class: 'chart',
    scales: { x: { time: false, distr: 3, log: 10 } },
    series: [{ label: 'frequency (Hz)' }, { label: 'amplitude (mm)', stroke: color, width: 1.5 }],
    legend: { live: false },
    axes: [{ label: 'frequency (Hz, log scale)',
             values: (u, splits) => splits.map(v => [0.1, 1, 10, 100, 1000].includes(Math.round(v * 1e6) / 1e6) ? String(v) : '') },
           { label: 'error amplitude (mm)', size: 60 }],
  }, [[], []], el);
  u.note = document.createElement('div');
  u.note.className = 'chart-note';
  u.note.textContent = 'spectrum after the first ' + waitS.toFixed(2) + ' s of the test (a full window)';
  u.over.appendChild(u.note);
  return u;
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
    const r = row(actuatorParent(a), 'Actuator ' + (a + 1));
    const c = COLORS[a % COLORS.length];
    V.plots.act.push({
      cmd: timePlot(r, 'command vs measured displacement', 'displacement (mm)', ['command (mm)', 'measured (mm)'], ['#1f5fbf', '#d1451b']),
      err: timePlot(r, 'tracking error (command − measured)', 'error (mm)', ['error (mm)'], [c]),
      spec: spectrumPlot(r, 'tracking error spectrum (last ' + h.spectrum_window_s.toFixed(2) + ' s, Hann)', c,
        h.spectrum_window_s),
      sync: xyPlot(r, 'synchronisation: measured vs command', 'command (mm)', 'measured (mm)', c),
      ti: timePlot(r, 'tracking indicator (grows when the actuator lags)', 'TI (mm²)', ['TI (mm²)'], [c]),
      hyst: xyPlot(r, 'force vs measured displacement', 'measured displacement (mm)', 'force (N)', c),
    });
  }
  h.links.forEach((id, l) => V.plots.link.push(timePlot(links, 'lag, ' + linkLabel(id),
    'lag (ms)', ['injected (ms)', 'measured round trip (ms)'], ['#2a8f2a', '#d1451b'])));
  // A controller link's own diagnostics (task time, overruns, valve, pressure...), one chart each.
  V.plots.diag = [];
  (h.diagnostics || []).forEach((names, l) => names.forEach((name, ch) =>
    V.plots.diag.push({ l, ch, plot: timePlot(links, 'controller diagnostic, ' + linkLabel(h.links[l]),
      name, [name], [COLORS[ch % COLORS.length]]) })));
  V.plots.deadlines = timePlot(links, 'overruns and late feedback so far', 'steps (count)',
    ['overruns (count)', 'late feedback (count)'], ['#c0221b', '#8e44ad']);
  V.plots.lateness = timePlot(links, 'lateness of each step (> 0 = overrun)', 'lateness (ms)', ['lateness (ms)'], ['#555']);
}

function reset(header, context) {
  V.header = header; V.context = context; V.spectra = []; V.events = []; V.drawnKey = null;
  V.cols = { step: [], time_s: [], lateness_ms: [], overruns: [], late_feedback: [] };
  for (const k of ['u_mm', 'predicted_u_mm', 'difference_mm'])
    V.cols[k] = Array.from({ length: header.dofs }, () => []);
  for (const k of ['command_mm', 'measured_mm', 'error_mm', 'force_N', 'ti_mm2'])
    V.cols[k] = Array.from({ length: header.actuators }, () => []);
  for (const k of ['injected_ms', 'round_trip_ms', 'answer_age_steps', 'answers', 'prediction_error_N'])
    V.cols[k] = Array.from({ length: header.links.length }, () => []);
  V.cols.diagnostics = (header.diagnostics || []).map(names => names.map(() => []));
  $('run').textContent = header.study + ' · case ' + header.case + ' · ' + header.clock.replace('_', ' ') +
    ' · dt ' + (header.dt_s * 1e3) + ' ms · run ' + header.run_id;
  const cd = (context && context.critical_delay) || {};
  $('critical').textContent = cd.margin_pct !== undefined
    ? cd.critical_delay_ms.toFixed(2) + ' ms, margin ' + cd.margin_pct.toFixed(0) + ' %' : (cd.text || '–');
  $('critical').title = cd.text || '';
  if (context && context.note) $('run').textContent += ' · ' + context.note;
  buildCharts();
  buildSites();
}

function append(dst, src) { for (let i = 0; i < src.length; i++) dst.push(src[i]); }

function merge(u) {
  if (u.header) reset(u.header, u.context);
  if (!V.cols) return;
  const s = u.samples;
  if (s && s.diagnostics)  // [link][channel][sample]: two levels deep
    s.diagnostics.forEach((chs, l) => chs.forEach((col, ch) => append(V.cols.diagnostics[l][ch], col)));
  if (s) for (const k of Object.keys(V.cols)) {
    if (!s[k] || k === 'diagnostics') continue;
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

// The indices drawn of the window [i0, i1): every k-th sample, k = ceil((i1 - i0) / width px),
// counted from the first sample received so the picks stay put as the window slides, and the
// newest sample. Whole samples: the plotted values are the record's at the steps drawn.
function picks(i0, i1, width) {
  const k = Math.max(1, Math.ceil((i1 - i0) / width)), idx = [];
  for (let i = Math.ceil(i0 / k) * k; i < i1; i += k) idx.push(i);
  if (i1 > i0 && idx[idx.length - 1] !== i1 - 1) idx.push(i1 - 1);
  return idx;
}

const at = (col, idx) => idx.map(i => col[i]);

// The newest spectrum up to time tEnd (s), or null.
function spectrumUpTo(tEnd) {
  let spec = null;
  for (const s of V.spectra) if (s.time_s <= tEnd + 1e-12) spec = s;
  return spec;
}

// The spectrum chart, only when its spectrum changed; its note shows while it has none.
function drawSpectrum(a, p, spec) {
  const step = spec ? spec.step : null;
  if (step === p.specStep && p.specDrawn) return;
  p.spec.setData(spec ? [V.header.spectrum_hz, spec.amplitude_mm[a]] : [[], []]);
  p.spec.note.hidden = spec !== null;
  p.specStep = step; p.specDrawn = true;
}

function drawActuator(a, p, t, idx, xy) {
  const c = V.cols;
  p.cmd.setData([t, at(c.command_mm[a], idx), at(c.measured_mm[a], idx)]);
  p.err.setData([t, at(c.error_mm[a], idx)]);
  p.ti.setData([t, at(c.ti_mm2[a], idx)]);
  p.sync.setData([null, [at(c.command_mm[a], xy), at(c.measured_mm[a], xy)]]);
  p.hyst.setData([null, [at(c.measured_mm[a], xy), at(c.force_N[a], xy)]]);
}

function drawResponse(t, idx) {
  const c = V.cols;
  V.plots.resp.forEach((p, d) => p.setData([t, at(c.u_mm[d], idx), at(c.predicted_u_mm[d], idx)]));
  V.plots.diff.setData([t, ...c.difference_mm.map(col => at(col, idx))]);
}

// Per floor, the measures `rths run` leads with, E_peak and E_rms of measured against predicted
// (%), then the largest and RMS difference (mm), so far (the feed's, over the samples compared).
function showPrediction(st) {
  const p = st.prediction;
  if (!p) { $('prediction-stats').textContent = ''; return; }
  $('prediction-stats').textContent = p.max_abs_difference_mm.map((m, d) => dofLabel(d) + ': ' +
    (m === 0 ? 'E_peak 0 %, E_rms 0 % (identical)'
      : 'E_peak ' + p.peak_error_pct[d].toFixed(2) + ' %, E_rms ' + p.rms_error_pct[d].toFixed(2) +
        ' % (max |measured − predicted| ' + m.toFixed(3) + ' mm, rms ' + p.rms_difference_mm[d].toFixed(3) + ' mm)')).join(' · ') +
    ' (over ' + p.compared_samples + ' samples)';
}

// Redraws what changed since the last draw: the time and x-y charts when the window of samples
// moved, each spectrum when its newest spectrum did. V.draws counts the draws that set data.
function draw() {
  V.drawPending = false; V.lastDrawMs = performance.now();
  if (V.status) showStatus(V.status);
  if (!V.cols) return;
  const [i0, i1] = visible(false), [x0, x1] = visible(true), c = V.cols;
  const key = [i0, i1, x0, x1].join();
  let drew = false;
  if (key !== V.drawnKey) {
    V.drawnKey = key; drew = true;
    const idx = picks(i0, i1, chartWidth()), xy = picks(x0, x1, chartWidth()), t = at(c.time_s, idx);
    V.plots.act.forEach((p, a) => { if (actuatorShown(a)) drawActuator(a, p, t, idx, xy); });
    drawResponse(t, idx);
    V.plots.link.forEach((p, l) => p.setData([t, at(c.injected_ms[l], idx), at(c.round_trip_ms[l], idx)]));
    V.plots.diag.forEach(d => d.plot.setData([t, at(c.diagnostics[d.l][d.ch], idx)]));
    V.plots.deadlines.setData([t, at(c.overruns, idx), at(c.late_feedback, idx)]);
    V.plots.lateness.setData([t, at(c.lateness_ms, idx)]);
    V.drawn = { i0, i1, steps: at(c.step, idx) };
  }
  const spec = spectrumUpTo(i1 ? c.time_s[i1 - 1] : 0);
  showSites();
  V.plots.act.forEach((p, a) => {
    if (!actuatorShown(a)) return;
    const before = p.specStep;
    drawSpectrum(a, p, spec);
    drew = drew || p.specStep !== before;
  });
  if (drew) V.draws++;
}

// A draw FPS times a second at most while live, on the next animation frame; none while hidden
// (a visibilitychange to visible schedules one).
function scheduleDraw() {
  if (V.drawPending || document.visibilityState === 'hidden') return;
  V.drawPending = true;
  const gap = V.mode === 'live' ? 1000 / V.fps : 0;
  const wait = Math.max(0, V.lastDrawMs + gap - performance.now());
  setTimeout(() => requestAnimationFrame(draw), wait);
}

document.addEventListener('visibilitychange', scheduleDraw);

// The state badge's text: a HOLD stays on it after the run stopped (the footer often follows it
// within an update). A run that ended shows its verdict's words (status.verdict.badge, e.g.
// "completed with deadline misses"), coloured by its level (ok, warning, failed).
function isHeld(st) { return st.state === 'HOLD' || V.events.some(e => e.what.startsWith('HOLD')); }
function badgeText(st) { return st.verdict ? st.verdict.badge : st.state; }
function stateText(st) { return isHeld(st) && st.state !== 'HOLD' ? 'HOLD · ' + badgeText(st) : badgeText(st); }
function badgeClass(st) { return isHeld(st) ? 'HOLD' : st.verdict ? st.verdict.level : st.state; }

// Beneath the badge: the reason of a HOLD or a stop, or the verdict of a run that ended (its
// text and failed node), coloured as it; below that, for a finished record, the deadline
// diagnosis.
function reasonText(st) {
  const node = st.node ? ' [' + st.node + ']' : '';
  if (!st.verdict) return st.state === 'completed' ? '' : (st.reason || '') + node;
  return st.verdict.text ? st.verdict.text + node : '';
}

// Writes the status line: at each draw, and at once when the state changes (see onUpdate).
function showStatus(st) {
  const held = isHeld(st), state = $('state');
  state.textContent = V.shownState = stateText(st);
  state.className = 'state ' + badgeClass(st);
  if (held && V.holdSeenMs === null) V.holdSeenMs = Date.now();
  $('step').textContent = st.latest_step < 0 ? '–' : st.latest_step;
  $('time').textContent = st.latest_time_s.toFixed(3);
  $('overruns').textContent = st.overruns;
  $('late').textContent = st.late_feedback;
  $('reason').textContent = reasonText(st);
  $('reason').className = st.verdict ? st.verdict.level : '';
  $('diagnosis').textContent = st.verdict ? st.verdict.diagnosis || '' : '';
  showControllers(st);
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

// Each controller node's link line and its hold, a row per frame: every HOLD frame sent (the
// position it carried), every answer while holding (what the rig measured, and whether it ended
// the hold) and the STOP frame.
function showControllers(st) {
  const list = st.controllers || [], box = $('controllers');
  $('controllers-box').hidden = list.length === 0;
  box.innerHTML = '';
  for (const c of list) {
    const p = document.createElement('p'); p.className = 'note'; p.textContent = c.link;
    box.appendChild(p);
    const rows = (c.hold && c.hold.entries) || [];
    if (!rows.length) continue;
    const table = document.createElement('table'); table.className = 'hold';
    const head = table.insertRow();
    for (const h of ['t ms', 'frame', 'kind', 'status', 'position mm', 'force N', 'verdict'])
      head.insertCell().textContent = h;
    for (const e of rows) {
      const r = table.insertRow();
      r.className = e.verdict && e.verdict !== 'held' && e.verdict !== 'holding' ? 'rejected' : '';
      for (const v of [(e.time_s * 1e3).toFixed(2), e.frame, e.kind, e.status,
        e.position_m.map(x => (x * 1e3).toFixed(3)).join(' '),
        e.force_N.map(x => x.toFixed(1)).join(' '), e.verdict])
        r.insertCell().textContent = v;
    }
    box.appendChild(table);
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
  slider.oninput = () => { $('slider-time').textContent = (+slider.value).toFixed(3); scheduleDraw(); };
}

function onUpdate(u) {
  V.updates++; V.mode = u.mode || V.mode;
  merge(u);
  V.status = u.status;
  if (stateText(u.status) !== V.shownState || u.status.finished) showStatus(u.status);
  if (u.events && u.events.length) showEvents();
  // A finished run, live or replayed, is shown whole, with the slider; there is nothing to stop.
  if (u.status.finished && V.source) {
    V.source.close(); V.source = null; V.mode = 'replay'; setupReplay();
    $('stop').disabled = true;
  }
  scheduleDraw();
}

// Which run this page shows where two are compared (/compare frames /?run=a and /?run=b).
const RUN_QUERY = new URLSearchParams(location.search).has('run')
  ? '?run=' + encodeURIComponent(new URLSearchParams(location.search).get('run')) : '';

// The stream is read with fetch, not EventSource, so that it can send this tab's role token
// (X-RTHS-Token; a run with roles serves its data to its crew only) in a header, never in a URL.
// Each event is `data: {json}` and a blank line. A refusal (401, 403) is shown and not retried.
async function connect() {
  const token = stopToken(), reader = { cancel: () => {} };
  V.source = { close: () => reader.cancel() };
  try {
    const r = await fetch('/api/stream' + RUN_QUERY, { headers: token ? { 'X-RTHS-Token': token } : {} });
    if (r.status === 401 || r.status === 403) { V.source = null; $('reason').textContent = await r.text(); return; }
    if (!r.ok) throw new Error('HTTP ' + r.status);
    const body = r.body.getReader(), decoder = new TextDecoder();
    reader.cancel = () => body.cancel();
    let text = '';
    for (;;) {
      const { value, done } = await body.read();
      if (done) break;
      text += decoder.decode(value, { stream: true });
      for (let end; (end = text.indexOf('\n\n')) >= 0; text = text.slice(end + 2)) {
        const event = text.slice(0, end);
        if (event.startsWith('data: ')) onUpdate(JSON.parse(event.slice(6)));
      }
    }
  } catch (e) { /* the connection ended: judged below */ }
  V.source = null;
  if (V.status && V.status.finished) return;
  $('reason').textContent = 'connection to the view lost (the coordinator has exited?); retrying';
  setTimeout(connect, 1000);
}

// The stop's token comes in the address the program printed (?token=..., as Jupyter's does):
// kept for this tab, so a reload still has it, and taken out of the address bar, so a screen
// shared or a screenshot does not show it. Without one the page asks for it.
function stopToken() {
  const params = new URLSearchParams(location.search);
  const given = params.get('token');
  if (given) {
    sessionStorage.setItem('rths-stop-token', given);
    params.delete('token');
    const rest = params.toString();
    history.replaceState(null, '', location.pathname + (rest ? '?' + rest : '') + location.hash);
  }
  return sessionStorage.getItem('rths-stop-token') || '';
}

async function setupStop() {
  const token = stopToken();
  V.health = await (await fetch('/api/health')).json();
  if (V.health.roles) return setupRoles(token);
  if (!V.health.stop_enabled) return;
  $('stop-box').hidden = false;
  $('token').hidden = !V.health.token_required || token !== '';
  $('stop').onclick = async () => {
    if (!confirm('Stop the test? The actuators HOLD, then every node STOPs.')) return;
    const r = await fetch('/api/stop', { method: 'POST', headers: { 'X-RTHS-Token': token || $('token').value } });
    $('reason').textContent = await r.text();
    if (r.ok) $('stop').disabled = true;
  };
}

setupStop();
connect();
