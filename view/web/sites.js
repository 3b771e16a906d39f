// The control room of the view (loaded after view.js, sharing its V and $): every site by name
// with its nodes, links and actuators (context.sites from `rths sites`; one site, "this host",
// otherwise), updated at each draw from the samples the page already holds; and the role's
// buttons (the director: HOLD any lab, STOP; a lab's operator: HOLD that lab).
// Per link, over the last STATS_S s of samples: round trip (median, ms), jitter (standard
// deviation of the round trip, ms), loss (1 - answers accepted / steps, %), drift (least-squares
// slope of the round trip over the kept samples after the first DRIFT_SKIP_S s, ms per s), against the critical round trip
// (context.critical_round_trip: compensated or uncompensated, as its label says; none where the
// compensated loop is stable for every round trip) with the margin left, 100 (critical - round
// trip) / critical %; the force predictor's largest |error| (N) and
// the answer age (ms, the step minus the step its answer answered, times dt) against the answer
// window (a real-time run's per node, context.answer_window_steps_by_node, at the run's start). Per actuator: command, measured, tracking error (mm, newest sample). Per node: HOLD and
// its cause (the record's events naming it).
'use strict';
const STATS_S = 2;
const DRIFT_SKIP_S = 1;

// [{name, nodes, lab_nodes}]: the sites config's, else one site holding every node.
function siteList() {
  const sites = (V.context || {}).sites;
  if (sites && sites.length) return sites;
  const nodes = [0].concat(V.header.links);
  return [{ name: 'this host', nodes, lab_nodes: nodes.filter(n => actuatorsOf(n).length) }];
}

function actuatorsOf(node) { return ((V.context || {}).node_actuators || {})[String(node)] || []; }

function siteOfActuator(a) {
  for (const s of siteList()) if (s.nodes.some(n => actuatorsOf(n).includes(a))) return s.name;
  return 'this host';
}

// The chart row of actuator a goes under its site's collapsible group; groups start closed when
// the run has more than 4 actuators, and a closed group's charts are not drawn.
function actuatorParent(a) {
  const id = 'acts-' + siteOfActuator(a);
  let group = document.getElementById(id);
  if (!group) {
    group = document.createElement('details'); group.id = id; group.className = 'site-charts';
    group.open = V.header.actuators <= 4;
    const summary = document.createElement('summary');
    summary.textContent = 'charts of ' + siteOfActuator(a) + "'s actuators";
    group.appendChild(summary);
    group.addEventListener('toggle', () => { V.drawnKey = null; scheduleDraw(); });
    $('actuators').appendChild(group);
  }
  return group;
}

function actuatorShown(a) {
  const group = document.getElementById('acts-' + siteOfActuator(a));
  return !group || group.open;
}

function cellRow(table, values, header) {
  const r = table.insertRow();
  for (const v of values) {
    const c = document.createElement(header ? 'th' : 'td'); c.textContent = v; r.appendChild(c);
  }
  return r;
}

function buildSites() {
  const box = $('sites'); box.innerHTML = '';
  const crit = (V.context || {}).critical_round_trip || {};
  $('sites-note').textContent = crit.ms !== undefined
    ? 'critical round trip ' + crit.ms.toFixed(1) + ' ms, ' + crit.label + ' (' + crit.text + ')'
    : crit.unbounded ? 'no critical round trip, ' + crit.label + ': stable for every round trip (' + crit.text + ')'
      : 'critical round trip: ' + (crit.text || 'not known');
  V.siteCells = { links: {}, acts: {}, nodes: {} };
  for (const site of siteList()) {
    const d = document.createElement('details'); d.open = true; d.className = 'site';
    d.id = 'site-' + site.name;
    const summary = document.createElement('summary');
    summary.innerHTML = '<b></b> <span class="note"></span> <span class="hold-buttons"></span>';
    summary.querySelector('b').textContent = site.name;
    summary.querySelector('.note').textContent = site.nodes.map(n => n ? linkLabel(n) : 'coordinator').join(', ');
    d.appendChild(summary);
    const table = document.createElement('table'); table.className = 'site-table';
    cellRow(table, ['node / actuator', 'state', 'round trip ms', 'jitter ms', 'loss %', 'drift ms/s',
      'margin to critical', 'predictor |error| N', 'answer age / window ms'], true);
    for (const n of site.nodes) {
      const r = cellRow(table, [n ? linkLabel(n) : 'coordinator (the integrator)', '', '', '', '', '', '', '', '']);
      V.siteCells.nodes[n] = r.cells[1];
      if (V.header.links.includes(n)) V.siteCells.links[n] = r;
      for (const a of actuatorsOf(n)) {
        const ar = cellRow(table, ['  actuator ' + (a + 1), '', '', '', '', '', '', '', '']);
        ar.className = 'actuator'; V.siteCells.acts[a] = ar.cells[1];
      }
    }
    d.appendChild(table); box.appendChild(d);
  }
  showHoldButtons();
}

const fmt = (x, digits) => (x === null || x === undefined || Number.isNaN(x)) ? '–' : x.toFixed(digits);

function lastWindow() {
  const t = V.cols.time_s, n = t.length;
  let i0 = n; while (i0 > 0 && t[i0 - 1] >= t[n - 1] - STATS_S) i0--;
  return [i0, n];
}

function linkStats(l, i0, i1) {
  const c = V.cols, rt = c.round_trip_ms[l].slice(i0, i1).filter(x => x > 0);
  const sorted = rt.slice().sort((a, b) => a - b), mean = rt.reduce((s, x) => s + x, 0) / (rt.length || 1);
  const sd = Math.sqrt(rt.reduce((s, x) => s + (x - mean) ** 2, 0) / Math.max(1, rt.length - 1));
  // Loss over the window from its first sample with an answer count (none before the first answer).
  const ans = c.answers[l], steps = c.step;
  let a0 = i0; while (a0 < i1 && ans[a0] === null) a0++;
  const loss = i1 - a0 > 1 && ans[i1 - 1] !== null
    ? 100 * (1 - (ans[i1 - 1] - ans[a0]) / Math.max(1, steps[i1 - 1] - steps[a0])) : null;
  // Least-squares slope of the round trip over the kept samples after the first DRIFT_SKIP_S s
  // (the start-up's first answers would read as drift), ms per s of test time.
  let n = 0, st = 0, sr = 0, stt = 0, str = 0;
  c.round_trip_ms[l].forEach((r, i) => {
    const x = c.time_s[i];
    if (!(r > 0) || x < DRIFT_SKIP_S) return;
    n++; st += x; sr += r; stt += x * x; str += x * r;
  });
  const drift = n > 2 && n * stt - st * st > 0 ? (n * str - st * sr) / (n * stt - st * st) : null;
  return { rt: sorted.length ? sorted[Math.floor(sorted.length / 2)] : null, jitter: rt.length > 1 ? sd : null, loss, drift };
}

// A node's HOLD: the first event that sent HOLD to it by its id (or that it sent itself), or to
// every actuator emulator (a node with actuators), or the run's HOLD while it has actuators. A run
// held from the view ("HOLD of the run ...") holds only the pressed lab's nodes: the others wait
// at their last command.
function nodeState(n) {
  const drives = actuatorsOf(n).length > 0;
  const held = V.events.filter(e => /HOLD|held/.test(e.what) &&
    (new RegExp('nodes? [0-9, ]*\\b' + n + '\\b').test(e.what) || (drives && /HOLD sent to the actuator emulators/.test(e.what))));
  if (held.length) return 'HOLD: ' + held[0].what;
  if (!V.status || V.status.state !== 'HOLD' || !drives) return '';
  if (/^HOLD of the run /.test(V.status.reason)) return 'at its last command: the run is held, no command leaves';
  return 'HOLD: ' + V.status.reason;
}

// At each draw: the tables' cells from the newest samples.
function showSites() {
  if (!V.siteCells || !V.cols || !V.cols.time_s.length) return;
  const c = V.cols, ctx = V.context || {}, dt = V.header.dt_s * 1e3, [i0, i1] = lastWindow();
  const crit = (ctx.critical_round_trip || {}).ms, unbounded = (ctx.critical_round_trip || {}).unbounded;
  V.header.links.forEach((id, l) => {
    const r = V.siteCells.links[id]; if (!r) return;
    const s = linkStats(l, i0, i1), age = c.answer_age_steps[l][i1 - 1];
    // A real-time run's window per node (its link's injected lag added), else the deployment's.
    const window = (ctx.answer_window_steps_by_node || {})[String(id)] || ctx.answer_window_steps;
    const margin = crit !== undefined && s.rt !== null ? fmt(crit - s.rt, 1) + ' ms (' + fmt(100 * (crit - s.rt) / crit, 0) + ' %) of ' + fmt(crit, 1)
      : unbounded ? 'unbounded (stable for every round trip)' : '–';
    const values = [fmt(s.rt, 2), fmt(s.jitter, 2), fmt(s.loss, 1), fmt(s.drift, 3), margin,
      fmt(c.prediction_error_N[l][i1 - 1], 1), fmt(age === null ? null : age * dt, 0) + ' / ' + fmt(window * dt, 0)];
    values.forEach((v, k) => { r.cells[k + 2].textContent = v; });
    r.cells[6].className = crit !== undefined && s.rt !== null && s.rt > crit ? 'past' : '';
  });
  for (const [a, cell] of Object.entries(V.siteCells.acts))
    cell.textContent = 'command ' + fmt(c.command_mm[a][i1 - 1], 3) + ' mm, measured ' +
      fmt(c.measured_mm[a][i1 - 1], 3) + ' mm, error ' + fmt(c.error_mm[a][i1 - 1], 4) + ' mm';
  // A finished run has nothing left to HOLD.
  if (V.status && V.status.finished) document.querySelectorAll('button.hold').forEach(b => { b.disabled = true; });
  for (const [n, cell] of Object.entries(V.siteCells.nodes)) {
    const text = nodeState(+n); cell.textContent = text || (V.status && V.status.finished ? V.status.state : 'armed');
    cell.className = text ? 'held' : '';
  }
}

// The role of the token this tab was given (POST /api/whoami), and its buttons.
async function setupRoles(token) {
  const r = await fetch('/api/whoami', { method: 'POST', headers: { 'X-RTHS-Token': token } });
  V.role = r.ok ? await r.json() : { role: 'none', name: 'no role (open the address printed for yours)' };
  V.token = token;
  $('role').hidden = false; $('role').textContent = 'you are ' + V.role.name;
  $('stop-box').hidden = V.role.role !== 'director';
  $('token').hidden = true;
  $('stop').onclick = () => press('stop', '', 'Stop the test? Every actuator HOLDs, then every node STOPs.');
  showHoldButtons();
}

function showHoldButtons() {
  if (!V.role || !$('sites')) return;
  for (const site of siteList()) {
    const span = document.querySelector('#site-' + CSS.escape(site.name) + ' .hold-buttons');
    if (!span || !site.lab_nodes.length) continue;
    span.innerHTML = '';
    if (V.role.role === 'director' || (V.role.role === 'operator' && V.role.lab === site.name)) {
      const b = document.createElement('button'); b.className = 'hold'; b.id = 'hold-' + site.name;
      b.textContent = 'HOLD ' + site.name;
      b.onclick = e => { e.preventDefault(); press('hold', site.name, 'HOLD ' + site.name + "'s actuators? The run then holds until the director stops it; nothing releases a HOLD."); };
      span.appendChild(b);
    }
  }
}

async function press(action, lab, question) {
  if (!confirm(question)) return;
  const r = await fetch('/api/' + action, { method: 'POST', headers: { 'X-RTHS-Token': V.token, 'X-RTHS-Lab': lab } });
  $('reason').textContent = await r.text();
}
