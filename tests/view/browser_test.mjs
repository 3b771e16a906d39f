// The view in a real browser (Debian's Chromium driven by playwright-core) over real runs:
// `rths launch --view` of a lockstep and of real-time runs over Cyclone DDS (domains 212-214),
// the page that stays on the finished run after it, and `rths view RECORD`. Skipped, with the
// reason printed, where Chromium cannot start.
// Screenshots go to RTHS_VIEW_TEST_OUT (view_lockstep.png, view_stays.png, view_live.png,
// view_hold.png, view_replay_early.png, view_replay.png). The page's drawing: ?fps=N caps its draws, none while
// hidden, decimated series are whole samples of the record, the spectrum's note before its first.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { spawn } from 'node:child_process';
import { createRequire } from 'node:module';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

const RTHS = process.env.RTHS_BIN;
const OUT = process.env.RTHS_VIEW_TEST_OUT;
const MOTION = path.resolve(process.env.RTHS_SOURCE_DIR, 'data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2');
const CHROMIUM = '/usr/bin/chromium';
const FLAGS = ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync'];

let context = null, skip = null;
let holdRecorded = false;  // the HOLD test's record, which the replay test opens
const children = [];

before(async () => {
  fs.mkdirSync(OUT, { recursive: true });
  let chromium;
  try {
    ({ chromium } = createRequire(process.env.RTHS_VIEW_NODE_MODULES + '/')('playwright-core'));
  } catch (e) { skip = 'playwright-core is not installed (the rths_view_web target runs npm ci): ' + e.message; }
  if (!skip && !fs.existsSync(CHROMIUM)) skip = CHROMIUM + ' is missing (apt-get install chromium)';
  if (!skip) {
    try {
      context = await chromium.launchPersistentContext(fs.mkdtempSync(path.join(os.tmpdir(), 'rths_chromium_')),
        { executablePath: CHROMIUM, headless: true, args: FLAGS, viewport: { width: 1500, height: 1000 }, timeout: 120000 });
    } catch (e) { skip = 'Chromium cannot start: ' + e.message.split('\n')[0]; }
  }
  if (skip) console.log('# SKIP the browser tests of the view: ' + skip);
});

after(async () => {
  for (const c of children) if (c.exitCode === null && c.signalCode === null) c.kill('SIGTERM');
  if (context) await context.close();
});

function study(dir, { clock, duration, domain }) {
  fs.rmSync(dir, { recursive: true, force: true });  // an earlier run's log names an old port
  fs.mkdirSync(dir, { recursive: true });
  const deployment = clock === 'REAL_TIME'
    // Fail-safe windows widened for this shared, loaded machine; the mechanism is the same.
    ? `deployment { domain_id: ${domain} clock: REAL_TIME liveliness_timeout: 1 heartbeat_period: 0.02 max_missed_answers: 300 command_watchdog_periods: 300 max_overrun_fraction: -1 }`
    : `deployment { domain_id: ${domain} }`;
  const text = `name: "view_test"
structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 } }
motion { path: "${MOTION}" duration: ${duration} }
integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }
substructuring { experimental_fraction: 0.3333333333333333 model { linear {} } }
cases { name: "lag_shift_14ms" delay { shift { delay: 0.014 } } }
${deployment}
`;
  fs.writeFileSync(path.join(dir, 'study.textproto'), text);
  return path.join(dir, 'study.textproto');
}

function start(args) {
  const child = spawn(RTHS, args, { stdio: ['ignore', 'pipe', 'pipe'] });
  child.output = '';
  child.stdout.on('data', d => { child.output += d; });
  child.stderr.on('data', d => { child.output += d; });
  child.done = new Promise(resolve => child.on('exit', code => resolve(code)));
  children.push(child);
  return child;
}

async function until(what, probe, ms = 60000) {
  const end = Date.now() + ms;
  for (;;) {
    const value = await probe();
    if (value) return value;
    if (Date.now() > end) throw new Error('timed out waiting for ' + what);
    await new Promise(r => setTimeout(r, 50));
  }
}

// `rths launch --view 127.0.0.1:0`: the coordinator's log names the port it got. A real-time
// launch that the project's own platform check refuses on this machine now comes back as
// { refused: what it measured }, and the test skips with it: a busy machine is no failure.
const REFUSED = "refusing to start: the deployment's fail-safe";
async function launchWithView(dir, config, domain, extra = []) {
  const child = start(['launch', config, '--domain', String(domain), '--out', dir, '--no-plots',
    '--view', '127.0.0.1:0', ...extra]);
  const log = path.join(dir, 'logs', 'lag_shift_14ms', 'coordinator.log');
  let refused = null;
  const url = await until('the view to listen', () => {
    if (child.exitCode !== null && child.output.includes(REFUSED)) return (refused = child.output);
    if (child.exitCode !== null) throw new Error('rths launch exited: ' + child.output);
    const text = fs.existsSync(log) ? fs.readFileSync(log, 'utf8') : '';
    const m = text.match(/live view at (http:\/\/\S+\/)/);
    return m && m[1];
  });
  if (refused) return { refused: 'the platform check refused the real-time run now:\n' + refused };
  return { child, url, log };
}

async function open(url) {
  const page = await context.newPage();
  page.on('dialog', d => d.accept());
  await page.goto(url);
  return page;
}

const view = (page, expr, arg) => page.evaluate(expr, arg);
const step = async page => Number(await page.textContent('#step')) || 0;

function csvColumns(file) {
  const [head, ...rows] = fs.readFileSync(file, 'utf8').trim().split('\n');
  const names = head.split(',');
  const cols = Object.fromEntries(names.map(n => [n, []]));
  for (const r of rows) r.split(',').forEach((v, i) => cols[names[i]].push(Number(v)));
  return cols;
}

test('lockstep over DDS: the step counter advances, the plotted series are the record\'s, the page stays on the finished run', { timeout: 300000 }, async t => {
  if (skip) return t.skip(skip);
  const dir = path.join(OUT, 'lockstep');
  const { child, url } = await launchWithView(dir, study(dir, { clock: 'LOCKSTEP', duration: 25, domain: 212 }), 212, ['--view-for', '120']);
  const page = await open(url);
  const first = await until('a first step on the page', () => step(page));
  // A lockstep run may finish before a loaded machine's page has drawn twice: then the page is on
  // its last state, which the next check reads.
  const finished = () => view(page, () => Boolean(window.rthsView.status && window.rthsView.status.finished));
  await until('the step counter to advance', async () => (await step(page)) > first || (await finished()));
  await until('the run\'s last state on the page', () => view(page, () => window.rthsView.status && window.rthsView.status.finished), 240000);
  // The finished run, whole, with its slider and its verdict; after the coordinator has exited,
  // launch serves it at the same address, and a reload shows it again.
  await until('the whole run on the page', () => page.isVisible('#slider'), 10000);
  assert.equal(await view(page, () => window.rthsView.mode), 'replay');
  assert.equal(await page.textContent('#state'), 'completed');
  await until('launch to keep the view', () => child.output.includes('rths launch: the view stays on the finished run of case lag_shift_14ms at ' + url), 60000);
  await page.reload();
  await until('the finished run after a reload', async () => (await view(page, () => window.rthsView.status && window.rthsView.status.finished)) && page.isVisible('#slider'), 30000);
  assert.equal(await view(page, () => window.rthsView.mode), 'replay');
  assert.equal(await page.textContent('#state'), 'completed');
  await until('the whole record drawn', () => view(page, () => window.rthsView.drawn &&
    window.rthsView.drawn.i1 === window.rthsView.cols.time_s.length), 10000);
  await page.screenshot({ path: path.join(OUT, 'view_stays.png'), fullPage: true });
  child.kill('SIGINT');  // Ctrl-C ends the kept view; launch exits with the run's status
  assert.equal(await child.done, 0, child.output);
  const exported = path.join(dir, 'record.csv');
  const ex = start(['export', path.join(dir, 'lag_shift_14ms.rthsrec'), '--csv', exported]);
  assert.equal(await ex.done, 0, ex.output);
  const csv = csvColumns(exported);
  const command = csv.command_act1_m, measured = csv.measured_act1_m;  // m, the record's columns
  assert.ok(command && measured, 'record columns: ' + Object.keys(csv).join(','));
  const plotted = await view(page, () => ({ steps: window.rthsView.drawn.steps, data: window.rthsView.plots.act[0].cmd.data,
    window: window.rthsView.drawn.i1 - window.rthsView.drawn.i0, width: window.rthsView.plots.act[0].cmd.width,
    noteHidden: window.rthsView.plots.act.map(p => p.spec.note.hidden) }));
  assert.ok(plotted.steps.length > 100, 'plotted points: ' + plotted.steps.length);
  // The 10 s window holds more samples than the chart has pixels: every k-th whole sample drawn.
  assert.ok(plotted.window > plotted.width && plotted.steps.length <= plotted.width + 2,
    `${plotted.steps.length} points drawn of ${plotted.window} samples on ${plotted.width} px`);
  assert.equal(plotted.data[0].length, plotted.steps.length);
  plotted.steps.forEach((s, i) => i && assert.ok(s > plotted.steps[i - 1], `steps drawn in order at ${i}`));
  assert.deepEqual(plotted.noteHidden, [true], 'the spectrum\'s note is gone once it has a spectrum');
  const row = Object.fromEntries(csv.step.map((s, i) => [s, i]));
  plotted.steps.forEach((s, i) => {
    assert.ok(Math.abs(plotted.data[1][i] - command[row[s]] * 1e3) <= 1e-9 * Math.max(1, Math.abs(plotted.data[1][i])), `command at step ${s}`);
    assert.ok(Math.abs(plotted.data[2][i] - measured[row[s]] * 1e3) <= 1e-9 * Math.max(1, Math.abs(plotted.data[2][i])), `measured at step ${s}`);
  });
  await checkPrediction(page, dir, csv, row, true);
  await checkSpectrum(page, csv, row);
  await page.screenshot({ path: path.join(OUT, 'view_lockstep.png'), fullPage: true });
  await page.close();
});

const near = (a, b, what) => assert.ok(Math.abs(a - b) <= 1e-9 * Math.max(1, Math.abs(b)), `${what}: ${a} vs ${b}`);

// The response against the in-process prediction: the predicted series is `rths run`'s (the
// in-process run of the same study and case) at the plotted steps, the measured one the record's,
// the page's largest |measured - predicted| that of the record's samples; lockstep over DDS
// equals the in-process run bit for bit (`lockstep`: that largest difference is 0).
async function checkPrediction(page, dir, csv, row, lockstep) {
  const out = path.join(dir, 'in_process');
  const run = start(['run', path.join(dir, 'study.textproto'), '--out', out, '--no-plots']);
  assert.equal(await run.done, 0, run.output);
  const inProcess = csvColumns(path.join(out, 'results.csv'));
  const predicted = inProcess.lag_shift_14ms_u_floor1_m;
  assert.ok(predicted, 'rths run columns: ' + Object.keys(inProcess).join(','));
  const p = await view(page, () => ({
    steps: window.rthsView.drawn.steps, data: window.rthsView.plots.resp[0].data,
    axes: window.rthsView.plots.resp[0].axes.map(a => a.label),
    stats: window.rthsView.status.prediction, text: document.querySelector('#prediction-text').textContent,
    statsText: document.querySelector('#prediction-stats').textContent,
    stride: window.rthsView.header.stride_steps,
  }));
  assert.ok(p.steps.length > 100, 'plotted points: ' + p.steps.length);
  const inRow = Object.fromEntries(inProcess.step.map((s, i) => [s, i]));
  p.steps.forEach((s, i) => {
    near(p.data[2][i], predicted[inRow[s]] * 1e3, `predicted at step ${s}`);
    near(p.data[1][i], csv.u_floor1_m[row[s]] * 1e3, `measured at step ${s}`);
  });
  assert.deepEqual(p.axes, ['time (s)', 'displacement (mm)']);
  assert.match(p.text, /in-process run of case lag_shift_14ms/);
  let largest = 0, compared = 0;
  csv.step.forEach((s, i) => {
    if (s % p.stride !== 0 || inRow[s] === undefined || Number.isNaN(predicted[inRow[s]])) return;
    largest = Math.max(largest, Math.abs(csv.u_floor1_m[i] * 1e3 - predicted[inRow[s]] * 1e3));
    compared++;
  });
  assert.equal(p.stats.compared_samples, compared, JSON.stringify(p.stats));
  near(p.stats.max_abs_difference_mm[0], largest, 'largest |measured - predicted|');
  if (lockstep) assert.equal(p.stats.max_abs_difference_mm[0], 0, 'lockstep equals the in-process run bit for bit');
  else assert.ok(largest > 0, 'real time differs from the in-process run');
  // The page leads with the measures `rths run` leads with: E_peak over the same samples.
  let peakPredicted = 0;
  csv.step.forEach((s) => {
    if (s % p.stride === 0 && inRow[s] !== undefined && !Number.isNaN(predicted[inRow[s]]))
      peakPredicted = Math.max(peakPredicted, Math.abs(predicted[inRow[s]] * 1e3));
  });
  near(p.stats.peak_error_pct[0], 100 * largest / peakPredicted, 'E_peak against the prediction');
  assert.match(p.statsText, /^floor 1: E_peak [0-9.]+ %, E_rms [0-9.]+ %/, p.statsText);
  assert.doesNotMatch(p.statsText, /NRMSE/, p.statsText);
}

// The tracking error's running spectrum on a log frequency axis: the plotted amplitudes are the
// Hann-windowed amplitude spectrum (2 |sum w_k e_k e^{-2 pi i f dt k}| / sum w, mm) of the
// record's command - measured over the window of steps ending at the spectrum's step, at the
// log-spaced frequencies the header lists.
async function checkSpectrum(page, csv, row) {
  const sp = await view(page, () => {
    const p = window.rthsView.plots.act[0];
    return { data: p.spec.data, step: p.specStep, distr: p.spec.scales.x.distr,
      axes: p.spec.axes.map(a => a.label), n: window.rthsView.header.spectrum_window_steps,
      dt: window.rthsView.header.dt_s, hz: window.rthsView.header.spectrum_hz };
  });
  assert.equal(sp.distr, 3, 'log frequency axis');
  assert.deepEqual(sp.axes, ['frequency (Hz, log scale)', 'error amplitude (mm)']);
  assert.ok(sp.step >= sp.n - 1 && sp.data[0].length > 30, `spectrum at step ${sp.step}`);
  assert.deepEqual(sp.data[0], sp.hz);
  near(sp.hz[0], 1 / (sp.n * sp.dt), 'lowest frequency');
  const e = [], w = [];
  for (let i = 0; i < sp.n; i++) {
    const k = row[sp.step - sp.n + 1 + i];
    e.push(csv.command_act1_m[k] * 1e3 - csv.measured_act1_m[k] * 1e3);
    w.push(0.5 - 0.5 * Math.cos(2 * Math.PI * i / sp.n));
  }
  const sum = w.reduce((a, b) => a + b, 0);
  const peak = Math.max(...sp.data[1]);
  assert.ok(peak > 0, 'a tracking error to analyse');
  sp.hz.forEach((f, b) => {
    let re = 0, im = 0;
    for (let i = 0; i < sp.n; i++) {
      re += e[i] * w[i] / sum * Math.cos(2 * Math.PI * f * sp.dt * i);
      im -= e[i] * w[i] / sum * Math.sin(2 * Math.PI * f * sp.dt * i);
    }
    assert.ok(Math.abs(sp.data[1][b] - 2 * Math.hypot(re, im)) <= 1e-9 * peak, `amplitude at ${f} Hz`);
  });
}

const sleep = ms => new Promise(r => setTimeout(r, ms));
const counts = page => view(page, () => ({ draws: window.rthsView.draws, updates: window.rthsView.updates,
  ms: performance.now(), step: window.rthsView.status.latest_step }));

// ?fps=N: while updates keep arriving, the page draws at most N times a second (draws are at least
// 1000/N ms apart; a slow machine only draws less), and still draws; the step on the page follows.
// Returns null, judging nothing, when no update came in the 3 s (the run is over: this machine
// let the page fall that far behind it), else how much slower than real time the page ran.
async function checkDrawRate(page, fps) {
  assert.equal(await view(page, () => window.rthsView.fps), fps);
  const a = await counts(page);
  await sleep(3000);
  const b = await counts(page);
  const draws = b.draws - a.draws, seconds = (b.ms - a.ms) / 1e3;
  console.log(`# ?fps=${fps}: ${draws} draws and ${b.updates - a.updates} updates in ${seconds.toFixed(1)} s`);
  if (b.updates === a.updates) return null;
  assert.ok(draws >= 1 && draws <= fps * seconds + 1, `${draws} draws in ${seconds} s at ?fps=${fps}`);
  assert.ok(b.updates - a.updates >= draws && b.step > a.step, 'updates merge at least as often as the page draws');
  return seconds / 3;
}

// The skip of a live-run test whose run ended before the page could act on it.
const endedFirst = what => `the run ended before ${what}: this machine lets the page fall seconds behind the run now`;
// A page that runs this much slower than real time cannot show a live run's events within their
// bounds: the test is skipped with the slowdown measured.
const kMaxSlowdown = 2;
const starved = slowdown => `this machine runs the page ${slowdown.toFixed(1)}x slower than real time now (a 3 s wait took ${(3 * slowdown).toFixed(1)} s): a live run's bounds cannot be judged`;

// Hidden (document.visibilityState): no draws while updates arrive; visible again: drawing resumes.
// Returns false, judging nothing, when no update came while hidden because the run ended (its
// `child`, rths launch, exits within 5 s); no update while the run goes on is a failure.
async function checkHidden(page, child) {
  const hide = hidden => view(page, h => {
    if (h) Object.defineProperty(document, 'visibilityState', { value: 'hidden', configurable: true });
    else delete document.visibilityState;
    document.dispatchEvent(new Event('visibilitychange'));
  }, hidden);
  await hide(true);
  await sleep(1000);  // a draw scheduled before hiding may still land
  const a = await counts(page);
  await sleep(2000);
  const b = await counts(page);
  assert.equal(b.draws, a.draws, 'no draws while hidden');
  if (b.updates === a.updates) {
    const ended = await until('rths launch to end', () => child.exitCode !== null, 5000).catch(() => false);
    if (ended) return false;
  }
  assert.ok(b.updates > a.updates, 'updates still merge while hidden (the run goes on)');
  await hide(false);
  await until('a draw once visible again', async () => (await counts(page)).draws > b.draws, 10000);
  return true;
}

// The substructure node's pid, found by its command line (domain and node id).
function nodePid(domain, program) {
  for (const pid of fs.readdirSync('/proc').filter(p => /^\d+$/.test(p))) {
    try {
      const args = fs.readFileSync(`/proc/${pid}/cmdline`, 'utf8').split('\0');
      if (args[0].endsWith(program) && args.includes(String(domain))) return Number(pid);
    } catch { /* gone meanwhile */ }
  }
  return null;
}

test('real time over DDS: a HOLD after a node is killed is on the page within 1 s', { timeout: 300000 }, async t => {
  if (skip) return t.skip(skip);
  const dir = path.join(OUT, 'hold');
  const { child, url, refused } = await launchWithView(dir, study(dir, { clock: 'REAL_TIME', duration: 30, domain: 213 }), 213, ['--view-for', '0']);
  if (refused) return t.skip(refused);
  const page = await open(url);
  await until('step 3000 on the page', async () => (await step(page)) > 3000);
  await page.screenshot({ path: path.join(OUT, 'view_live.png'), fullPage: true });
  const slowdown = await checkDrawRate(page, 10);  // the default cap
  const pid = nodePid(213, 'rths-substructure-node');
  if (slowdown === null || (!pid && child.exitCode !== null)) return t.skip(endedFirst('its node could be killed'));
  if (slowdown > kMaxSlowdown) return t.skip(starved(slowdown));
  assert.ok(pid, 'the substructure node is running');
  process.kill(pid, 'SIGKILL');
  await until('HOLD on the page', () => view(page, () => window.rthsView.holdSeenMs), 20000);
  const { seen, hold } = await view(page, () => ({
    seen: window.rthsView.holdSeenMs,
    hold: window.rthsView.events.find(e => e.what.startsWith('HOLD')),
  }));
  assert.ok(hold, 'the record\'s HOLD event reached the page');
  const delay = seen - hold.realtime_ns / 1e6;
  console.log(`# HOLD on the page ${delay.toFixed(0)} ms after the coordinator sent it (page ${slowdown.toFixed(1)}x slower than real time)`);
  // Within 1 s on a machine that runs the page in real time; a starved page gets its measured
  // slowdown on top.
  const bound = 1000 * Math.max(1, slowdown);
  assert.ok(delay < bound, `HOLD shown ${delay} ms after it was sent (bound ${bound} ms)`);
  assert.match(await page.textContent('#state'), /^HOLD/);
  await page.screenshot({ path: path.join(OUT, 'view_hold.png'), fullPage: true });
  assert.notEqual(await child.done, 0);
  holdRecorded = true;
  await page.close();
});

test('real time over DDS: the stop button stops the run, HOLD then STOP, "stopped from the view"', { timeout: 300000 }, async t => {
  if (skip) return t.skip(skip);
  const dir = path.join(OUT, 'stop');
  const { child, url, log, refused } = await launchWithView(dir, study(dir, { clock: 'REAL_TIME', duration: 30, domain: 214 }), 214, ['--view-stop', '--view-for', '0']);
  if (refused) return t.skip(refused);
  // The stop's token: made by rths launch and printed in the address to open (loopback too).
  const token = (child.output.match(/live view of each case at \S+\?token=([0-9a-f]{32}) /) || [])[1];
  assert.ok(token, 'rths launch printed no stop token: ' + child.output);
  const page = await open(url + '?token=' + token + '&fps=2');
  await until('step 1000 on the page', async () => (await step(page)) > 1000);
  assert.ok(!page.url().includes('token'), 'the token is taken out of the address bar: ' + page.url());
  // Another origin (localhost is not 127.0.0.1 to the browser) posting to the stop, as any
  // web page may: refused, and the run goes on.
  const other = await open(url.replace('127.0.0.1', 'localhost'));
  await view(other, target => fetch(target + 'api/stop', { method: 'POST', mode: 'no-cors' }).catch(() => null), url);
  // A loaded machine's run can end (its fail-safe, its deadlines) while the page is behind it;
  // with --view-for 0 the view goes with it. That is skipped naming the run's end; a view that
  // went away while its run still goes on is a failure.
  const health = await view(page, () => fetch('/api/health').then(r => r.json())).catch(async e => {
    await sleep(500);
    if (child.exitCode === null) throw e;
    return null;
  });
  if (health === null)
    return t.skip(endedFirst('the cross-origin stop could be judged') + '; rths launch: ' + child.output.slice(-600));
  assert.equal(health.counters.cross_origin, 1, JSON.stringify(health.counters));
  assert.equal(health.counters.stop_requests, 0, JSON.stringify(health.counters));
  await other.close();
  const slowdown = await checkDrawRate(page, 2);
  if (slowdown === null) return t.skip(endedFirst('the draw rate could be seen'));
  if (slowdown > kMaxSlowdown) return t.skip(starved(slowdown));
  if (!(await checkHidden(page, child))) return t.skip(endedFirst('the hidden page could be judged'));
  // The page disables its stop once it sees the run finished: a button that stays disabled while
  // rths launch goes on is a failure; one whose run ended (its fail-safe, its deadlines) skips.
  const pressed = await page.click('#stop', { timeout: 15000 }).then(() => true, async e => {
    const ended = await until('rths launch to end', () => child.exitCode !== null, 15000).catch(() => false);
    if (!ended) throw e;
    return false;
  });
  if (!pressed) return t.skip(endedFirst('its stop button could be pressed') + '; rths launch: ' + child.output.slice(-600));
  const code = await until('rths launch to end', () => child.exitCode !== null ? { code: child.exitCode } : null, 30000);
  const summary = JSON.parse(fs.readFileSync(path.join(dir, 'summary.json'), 'utf8'));
  if (code.code === 0 && summary.cases[0].status === 'completed') return t.skip(endedFirst('the stop reached it'));
  assert.equal(code.code, 1, child.output);
  assert.equal(summary.cases[0].status, 'stopped from the view', JSON.stringify(summary.cases[0]));
  const text = fs.readFileSync(log, 'utf8');
  assert.match(text, /HOLD sent to the actuator emulators: stopped from the view/);
  assert.ok(summary.cases[0].steps === undefined || summary.cases[0].steps < 30000);
  await page.close();
});

test('rths view RECORD: the finished record with a time slider', { timeout: 120000 }, async t => {
  if (skip) return t.skip(skip);
  const record = path.join(OUT, 'hold', 'lag_shift_14ms.rthsrec');
  if (!holdRecorded) return t.skip('the HOLD test did not record a held run (see its result)');
  const server = start(['view', record, '--listen', '127.0.0.1:0', '--for', '100']);
  const url = await until('rths view to listen', () => {
    if (server.exitCode !== null) throw new Error('rths view exited: ' + server.output);
    const m = server.output.match(/at (http:\/\/\S+\/)/);
    return m && m[1];
  });
  const page = await open(url);
  await until('the slider', () => page.isVisible('#slider'));
  assert.equal(await view(page, () => window.rthsView.mode), 'replay');
  // The draw after the last update: the whole record, its last spectrum, no note.
  await until('the whole record drawn', () => view(page, () => window.rthsView.drawn &&
    window.rthsView.drawn.i1 === window.rthsView.cols.time_s.length), 10000);
  const all = await view(page, () => window.rthsView.drawn.i1);
  await until('no spectrum note at the record\'s end', async () => !(await page.isVisible('.chart-note')), 10000);
  // Before the first full window of steps the spectrum chart says when its spectrum comes.
  const firstS = await view(page, () => window.rthsView.header.spectrum_window_s / 2);
  await page.$eval('#slider', (s, v) => { s.value = String(v); s.dispatchEvent(new Event('input')); }, firstS);
  await until('the spectrum note before the first spectrum', () => page.isVisible('.chart-note'), 10000);
  assert.match(await page.textContent('.chart-note'), /^spectrum after the first \d+\.\d\d s of the test \(a full window\)$/);
  assert.deepEqual(await view(page, () => window.rthsView.plots.act[0].spec.data[1]), []);
  await page.screenshot({ path: path.join(OUT, 'view_replay_early.png'), fullPage: true });
  await page.$eval('#slider', s => { s.value = String(Number(s.max) / 2); s.dispatchEvent(new Event('input')); });
  await until('the charts to follow the slider', () => view(page, n => window.rthsView.drawn.i1 < n, all));
  await until('the spectrum note gone with a spectrum', async () => !(await page.isVisible('.chart-note')), 10000);
  assert.equal(await page.textContent('#state'), 'HOLD · stopped');
  const exported = path.join(OUT, 'hold', 'record.csv');
  const ex = start(['export', record, '--csv', exported]);
  assert.equal(await ex.done, 0, ex.output);
  const csv = csvColumns(exported);
  await checkPrediction(page, path.join(OUT, 'hold'), csv, Object.fromEntries(csv.step.map((s, i) => [s, i])), false);
  await page.screenshot({ path: path.join(OUT, 'view_replay.png'), fullPage: true });
  server.kill('SIGTERM');
  await server.done;
  await page.close();
});
