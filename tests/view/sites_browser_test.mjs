// The control room in a real browser (Debian's Chromium driven by playwright-core) over real
// `rths sites --view --view-stop` runs: three sites in network namespaces (site_a: the coordinator
// and the numerical storeys; lab_b and lab_c: two actuators each), lockstep over Cyclone DDS
// (domains 1 and 2). The page names every site with its nodes, links and actuators; an operator's
// HOLD of their lab reaches its actuators within the answer window and holds the run (no further
// step, the process goes on, the page says HOLD, lab_c gets no HOLD and no command) until the
// director's stop ends it (exit 1, the record complete); an operator cannot stop the run or HOLD
// another lab; a page without a role's token reads nothing; a viewer's stop is refused; the
// director's stop ends a running run; the record (read back by `rths view` of the run's folder,
// with its sites) names who pressed what; `rths view A --compare B` shows both runs. Skipped,
// with the reason printed, where Chromium cannot start or network namespaces cannot be made.
// Screenshots (the first 1000 px: the header and the sites) go to RTHS_VIEW_TEST_OUT
// (sites_operator.png, sites_hold.png, sites_held_director.png, sites_held_stop.png,
// sites_no_token.png, sites_viewer.png, sites_director_stop.png, sites_compare.png).
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { spawn, spawnSync } from 'node:child_process';
import { createRequire } from 'node:module';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

const RTHS = process.env.RTHS_BIN;
const BIN_DIR = process.env.RTHS_BINARY_DIR;
const OUT = process.env.RTHS_VIEW_TEST_OUT;
const MOTION = path.resolve(process.env.RTHS_SOURCE_DIR, 'data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2');
const CHROMIUM = '/usr/bin/chromium';
const FLAGS = ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync'];

let context = null, skip = null;
const children = [];

before(async () => {
  fs.mkdirSync(OUT, { recursive: true });
  if (process.getuid && process.getuid() !== 0) skip = 'network namespaces need root';
  let chromium;
  try {
    ({ chromium } = createRequire(process.env.RTHS_VIEW_NODE_MODULES + '/')('playwright-core'));
  } catch (e) { skip = skip || 'playwright-core is not installed (the rths_view_web target runs npm ci): ' + e.message; }
  if (!skip && !fs.existsSync(CHROMIUM)) skip = CHROMIUM + ' is missing (apt-get install chromium)';
  if (!skip) {
    try {
      context = await chromium.launchPersistentContext(fs.mkdtempSync(path.join(os.tmpdir(), 'rths_chromium_')),
        { executablePath: CHROMIUM, headless: true, args: FLAGS, viewport: { width: 1500, height: 1000 }, timeout: 120000 });
    } catch (e) { skip = 'Chromium cannot start: ' + e.message.split('\n')[0]; }
  }
  if (skip) console.log('# SKIP the browser tests of the control room: ' + skip);
});

after(async () => {
  for (const c of children) if (c.exitCode === null && c.signalCode === null) c.kill('SIGINT');
  if (context) await context.close();
});

// A 4-storey shear frame, a third of each storey experimental (four actuators); lab_b's emulator
// hosts storeys 1-2, lab_c's 3-4; 1 ms each way on every link, with jitter; 20 s of El Centro,
// longer than the test lets it run.
function sites(dir, domain, subnet) {
  fs.rmSync(dir, { recursive: true, force: true });
  fs.mkdirSync(dir, { recursive: true });
  fs.writeFileSync(path.join(dir, 'study.textproto'), `name: "control_room"
structure {
  shear_building { storey_mass: [1000, 1000, 1000, 1000] storey_stiffness: [4e5, 3.5e5, 3e5, 2.5e5] }
  damping { modal_zeta: 0.05 }
}
motion { path: "${MOTION}" duration: 20 }
integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }
substructuring { experimental_fraction: 0.3333333333333333 model { linear {} } }
cases { name: "lab_test" delay { shift { delay: 0.002 } } }
`);
  const link = (id, seed) => `links { node_id: ${id}
  to_node { one_way_delay: 0.001 jitter: 0.0002 seed: ${seed} }
  from_node { one_way_delay: 0.001 jitter: 0.0002 seed: ${seed + 1} } }\n`;
  fs.writeFileSync(path.join(dir, 'sites.textproto'), `study: "study.textproto"
case_name: "lab_test"
domain_id: ${domain}
subnet: "${subnet}"
clock: LOCKSTEP
timeout: 240
sites { name: "site_a" node_ids: [0, 1] }
sites { name: "lab_b" node_ids: 2 }
sites { name: "lab_c" node_ids: 3 }
${link(1, 11)}${link(2, 21)}${link(3, 31)}
deployment {
  nodes { id: 1 kind: SUBSTRUCTURE }
  nodes { id: 2 kind: ACTUATOR_EMULATOR storeys: [1, 2] }
  nodes { id: 3 kind: ACTUATOR_EMULATOR storeys: [3, 4] }
  start_timeout: 30
}
`);
  return path.join(dir, 'sites.textproto');
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

async function until(what, probe, ms = 90000) {
  const end = Date.now() + ms;
  for (;;) {
    const value = await probe();
    if (value) return value;
    if (Date.now() > end) throw new Error('timed out waiting for ' + what);
    await new Promise(r => setTimeout(r, 100));
  }
}

// `rths sites --view 127.0.0.1:0 --view-stop`: the role addresses it prints, once.
async function startSites(dir, domain, subnet) {
  const child = start(['sites', sites(dir, domain, subnet), '--view', '127.0.0.1:0', '--view-stop',
    '--bin-dir', BIN_DIR, '--out', path.join(dir, 'out'), '--no-plots']);
  const roles = await until('the control room\'s addresses', () => {
    if (child.exitCode !== null) throw new Error('rths sites exited: ' + child.output);
    const viewer = child.output.match(/viewer \(sees only\): (\S+)/);
    if (!viewer) return null;
    const r = { viewer: viewer[1], director: child.output.match(/director \(HOLD any lab, STOP\): (\S+)/)[1] };
    for (const lab of ['lab_b', 'lab_c'])
      r[lab] = child.output.match(new RegExp('operator of ' + lab + ' \\(HOLD ' + lab + "'s actuators\\): (\\S+)"))[1];
    return r;
  });
  return { child, roles };
}

async function open(url) {
  const page = await context.newPage();
  page.on('dialog', d => d.accept());
  await page.goto(url);
  return page;
}

const view = (page, expr, arg) => page.evaluate(expr, arg);
const step = async page => Number(await page.textContent('#step')) || 0;
// A POST from the page itself, with the token the page holds (as its buttons send it).
const post = (page, action, lab) => view(page, async ([a, l]) => {
  const r = await fetch('/api/' + a, { method: 'POST', headers: { 'X-RTHS-Token': window.rthsView.token, 'X-RTHS-Lab': l } });
  return { status: r.status, text: await r.text() };
}, [action, lab]);

// The page names every site, under it its nodes and actuators, and per link its figures.
async function checkSites(page) {
  await until('the sites on the page', async () => (await step(page)) > 300 &&
    (await page.textContent('#site-lab_b table')).includes('round trip'));
  const tables = await view(page, () => Object.fromEntries([...document.querySelectorAll('details.site')].map(d =>
    [d.id, [...d.querySelectorAll('tr')].map(r => [...r.cells].map(c => c.textContent))])));
  assert.deepEqual(Object.keys(tables), ['site-site_a', 'site-lab_b', 'site-lab_c']);
  const names = rows => rows.slice(1).map(r => r[0].trim());
  assert.deepEqual(names(tables['site-site_a']), ['coordinator (the integrator)', 'node 1 (substructure)']);
  assert.deepEqual(names(tables['site-lab_b']), ['node 2 (actuator emulator)', 'actuator 1', 'actuator 2']);
  assert.deepEqual(names(tables['site-lab_c']), ['node 3 (actuator emulator)', 'actuator 3', 'actuator 4']);
  const link = tables['site-lab_b'][1];
  // Round trip: the 2 ms the node injects and the exchange; the margin against the critical one.
  assert.ok(Number(link[2]) >= 2 && Number(link[2]) < 50, 'round trip ' + link[2]);
  assert.match(link[6], /ms \(\d+ %\) of \d/);
  assert.equal(link[4], '0.0', 'lockstep answers every step: no loss');
  assert.match(tables['site-lab_b'][2][1], /^command -?\d+\.\d+ mm, measured -?\d+\.\d+ mm, error/);
  assert.match(await page.textContent('#sites-note'), /critical round trip \d+\.\d ms, uncompensated/);
}

// The events of a finished record as `rths view` serves them.
async function recordEvents(record) {
  const child = start(['view', record, '--listen', '127.0.0.1:0', '--for', '60']);
  const url = await until('rths view to listen', () => (child.output.match(/(http:\/\/127\.0\.0\.1:\d+\/)/) || [])[1]);
  const snapshot = await (await fetch(url + 'api/snapshot')).json();
  child.kill('SIGINT');
  await child.done;
  return { events: snapshot.events.map(e => e.what), context: snapshot.context, header: snapshot.header,
    status: snapshot.status };
}

test('an operator HOLDs their own lab within the answer window and the run holds until the director stops it; another lab and STOP are refused (403) and recorded', { timeout: 400000 }, async t => {
  if (skip) return t.skip(skip);
  const dir = path.join(OUT, 'sites_hold');
  const { child, roles } = await startSites(dir, 1, '10.231.201');
  const page = await open(roles.lab_b);
  await checkSites(page);
  assert.equal(new URL(page.url()).search, '', 'the token is out of the address bar');
  await until('the operator\'s role', async () => (await page.textContent('#role')) === 'you are the operator of lab_b', 10000);
  assert.equal(await page.isVisible('#stop'), false);
  assert.equal(await page.isVisible('#hold-lab_c'), false);
  assert.equal(await page.isVisible('#hold-lab_b'), true);
  await page.screenshot({ path: path.join(OUT, 'sites_operator.png') });
  const other = await post(page, 'hold', 'lab_c');
  assert.equal(other.status, 403, other.text);
  assert.match(other.text, /may HOLD only lab_b's actuators/);
  assert.equal((await post(page, 'stop', '')).status, 403);
  await page.click('#hold-lab_b');
  await until('the HOLD on the page', async () => (await page.textContent('#state')).startsWith('HOLD'));
  await until('lab_b\'s actuators held on the page', async () =>
    (await page.textContent('#site-lab_b table')).includes('HOLD: the operator of lab_b pressed HOLD of lab_b'));
  // Held: the run goes on without a step (the page's newest step stays) and the process stays.
  const heldStep = await step(page);
  await new Promise(r => setTimeout(r, 3000));
  assert.equal(await step(page), heldStep, 'no step is integrated past the HOLD');
  assert.equal(child.exitCode, null, 'the held run waits for the director: ' + child.output);
  assert.match(await page.textContent('#site-lab_c table'), /at its last command: the run is held, no command leaves/);
  await page.screenshot({ path: path.join(OUT, 'sites_hold.png') });
  const director = await open(roles.director);
  await until('the HOLD on the director\'s page', async () => (await director.textContent('#state')).startsWith('HOLD'));
  await director.screenshot({ path: path.join(OUT, 'sites_held_director.png') });
  await director.click('#stop');
  await until('the stop on the page', async () => (await director.textContent('#reason')).includes('stopped from the view by the director'), 60000);
  await director.screenshot({ path: path.join(OUT, 'sites_held_stop.png') });
  // A run that did not complete its purpose: exit 1, as for any stopped run.
  assert.equal(await child.done, 1, child.output);
  assert.match(child.output, /stopped from the view by the director \(held: HOLD from the view by the operator of lab_b\)/);
  // `rths view OUT`: the run's folder, its sites as the live page had them (OUT/sites.json).
  const { events, context, status } = await recordEvents(path.join(dir, 'out'));
  assert.deepEqual(context.sites.map(site => [site.name, site.nodes, site.lab_nodes]),
    [['site_a', [0, 1], []], ['lab_b', [2], [2]], ['lab_c', [3], [3]]]);
  const held = events.find(e => e.startsWith('the operator of lab_b pressed HOLD of lab_b on the view: HOLD sent to node 2; the run holds until the director stops it'));
  assert.ok(held, events.join('\n'));
  // The HOLD left at the step that applied the press; the loop was at least at the newest step the
  // view had seen when it was pressed, so their difference bounds the delay in steps.
  const [, applied, seen, ms] = held.match(/applied at step (\d+), the view had seen step (\d+); ([\d.]+) ms after the press/).map(Number);
  assert.ok(applied - seen <= context.answer_window_steps,
    `HOLD sent at step ${applied}, pressed at step ${seen} or later (${ms} ms), answer window ${context.answer_window_steps} steps`);
  // The record is complete (its footer read) and ends at the step before the one the HOLD stopped.
  assert.equal(status.finished, true);
  assert.equal(status.footer.status, 'stopped from the view by the director (held: HOLD from the view by the operator of lab_b)');
  assert.equal(status.latest_step, applied - 1, 'no step integrated past the HOLD');
  assert.ok(events.some(e => e.startsWith(`HOLD of the run at step ${applied}: HOLD from the view by the operator of lab_b`)), events.join('\n'));
  // lab_c (node 3) stayed at its last command: no HOLD and no HOLD of its own until the director's STOP.
  const stopAt = events.findIndex(e => e.startsWith('the director pressed STOP on the view: HOLD, then STOP'));
  assert.ok(stopAt > 0, events.join('\n'));
  assert.ok(!events.slice(0, stopAt).some(e => /node 3|HOLD sent to the actuator emulators/.test(e)), events.join('\n'));
  assert.ok(events.some(e => e.startsWith('the operator of lab_b pressed HOLD of lab_c on the view: refused (403)')), events.join('\n'));
  assert.ok(events.some(e => e.startsWith('the operator of lab_b pressed STOP on the view: refused (403), only the director may stop the test')), events.join('\n'));
  assert.ok(events.slice(stopAt).some(e => /^HOLD sent to the actuator emulators: stopped from the view by the director/.test(e)), events.join('\n'));
  await page.close();
  await director.close();
});

test('a viewer\'s stop is refused (403) and recorded; the director\'s stop ends the run', { timeout: 400000 }, async t => {
  if (skip) return t.skip(skip);
  const dir = path.join(OUT, 'sites_stop');
  const { child, roles } = await startSites(dir, 2, '10.231.202');
  // Without a role's token the run's data is refused and the page says why.
  const stranger = await open(new URL(roles.viewer).origin + '/');
  await until('the refusal on a page without a token', async () => (await stranger.textContent('#reason')).includes('is for its crew'));
  assert.equal(await step(stranger), 0);
  await stranger.screenshot({ path: path.join(OUT, 'sites_no_token.png') });
  await stranger.close();
  const viewer = await open(roles.viewer);
  await checkSites(viewer);
  // The role comes from its own request, which may answer after the stream's first samples.
  await until('the viewer\'s role', async () => (await viewer.textContent('#role')) === 'you are a viewer', 10000);
  assert.equal(await viewer.isVisible('#stop'), false);
  assert.equal(await viewer.locator('button.hold').count(), 0);
  const refused = await post(viewer, 'stop', '');
  assert.equal(refused.status, 403, refused.text);
  assert.match(refused.text, /a viewer pressed STOP on the view: refused \(403\)/);
  await viewer.screenshot({ path: path.join(OUT, 'sites_viewer.png') });
  const director = await open(roles.director);
  await checkSites(director);
  await until('the director\'s role', async () => (await director.textContent('#role')) === 'you are the director', 10000);
  assert.equal(await director.locator('button.hold').count(), 2);  // lab_b's and lab_c's
  await director.click('#stop');
  await until('the stop on the page', async () => (await director.textContent('#reason')).includes('stopped from the view by the director'), 60000);
  await until('the HOLD buttons off once the run is over', () => view(director, () =>
    [...document.querySelectorAll('button.hold')].every(b => b.disabled)), 30000);
  await director.screenshot({ path: path.join(OUT, 'sites_director_stop.png') });
  assert.equal(await child.done, 1, child.output);
  const { events } = await recordEvents(path.join(dir, 'out', 'lab_test.rthsrec'));
  assert.ok(events.some(e => e.startsWith('a viewer pressed STOP on the view: refused (403)')), events.join('\n'));
  assert.ok(events.some(e => e.startsWith('the director pressed STOP on the view: HOLD, then STOP')), events.join('\n'));
  await viewer.close();
  await director.close();
});

// `rths view A --compare B`: the held run and the stopped run of the tests above side by side,
// each run's E_peak and E_rms above its own page.
test('rths view OUT_A --compare OUT_B shows both runs side by side with each one\'s E_peak and E_rms', { timeout: 120000 }, async t => {
  if (skip) return t.skip(skip);
  const [a, b] = ['sites_hold', 'sites_stop'].map(name => path.join(OUT, name, 'out'));
  // The tests above ran (nothing skipped them), so their runs' folders are theirs to leave: one
  // missing is their failure, never a reason to skip this one.
  for (const dir of [a, b]) assert.ok(fs.existsSync(dir), `${dir}: the run of a test above is missing`);
  const child = start(['view', a, '--compare', b, '--listen', '127.0.0.1:0', '--for', '60']);
  const url = await until('rths view to listen', () => (child.output.match(/(http:\/\/127\.0\.0\.1:\d+\/)/) || [])[1]);
  const page = await open(url + 'compare');
  await until('both runs in the table', async () => (await page.locator('#runs tbody tr').count()) === 2);
  const rows = await view(page, () => [...document.querySelectorAll('#runs tbody tr')].map(r => [...r.cells].map(c => c.textContent)));
  assert.match(rows[0][1], /sites_hold\/out\/lab_test\.rthsrec$/);
  assert.match(rows[1][1], /sites_stop\/out\/lab_test\.rthsrec$/);
  assert.match(rows[0][3], /held: HOLD from the view by the operator of lab_b/);
  for (const row of rows) assert.match(row[5], /^floor 1 \d+\.\d\d, floor 2 /, row.join(' | '));
  for (const [frame, run] of [['#page-a', 'a'], ['#page-b', 'b']]) {
    const inner = page.frameLocator(frame);
    await until('run ' + run + "'s page", async () => (await inner.locator('details.site').count()) === 3);
  }
  await page.screenshot({ path: path.join(OUT, 'sites_compare.png') });
  child.kill('SIGINT');
  await child.done;
  await page.close();
});
