// cncjs 1.11.5 drives `motionctl serve`: its server runs headless on
// 127.0.0.1 with a config file of ours, this script talks to it as its web
// page would (socket.io, a token signed with the config's secret), opens the
// serve's pseudo-terminal as a Grbl port, loads a job, starts it, holds and
// resumes it, raises the feed override, and waits until the workflow is idle
// with every line acknowledged and the machine at the job's end point.
//
// usage: node test_grbl_cncjs.js MOTIONCTL CNCJS_DIR [--dry-run|--sim|--cycles]
//   CNCJS_DIR: where scripts/deps.sh installed cncjs (node_modules/cncjs).
//   --sim: `motionctl --sim serve`, the board backend on a virtual board of
//   the test's own (a private runtime directory, stopped at the end), with a
//   shorter job: it runs in real time. MPos is then the encoders' position,
//   which a stop reports once the servo is within 2 counts (5 um) of its
//   command.
//   --cycles: a job's start as an operator does it, on the virtual board.
//   Before the sender connects, `motionctl home` and `motionctl level probe`
//   map the bed (the server holds the board while it serves), and `serve
//   --level` takes the map. Then cncjs homes ($H, after $22=1), moves over
//   the map's first point, probes Z down to the work (G38.2, as its probe
//   widget does), sets work Z0 there (G10 L20), and runs an engraving 0.1 mm
//   deep that ends on the map's point furthest from the first one's height:
//   the work Z there must be -0.1 mm plus the map's height, which the server
//   added.
'use strict';

const { spawn } = require('child_process');
const fs = require('fs');
const net = require('net');
const os = require('os');
const path = require('path');

const [motionctl, cncjsDir, mode = '--dry-run'] = process.argv.slice(2);
const sim = mode === '--sim' || mode === '--cycles';
if (mode !== '--dry-run' && !sim) {
  console.error('usage: node test_grbl_cncjs.js MOTIONCTL CNCJS_DIR [--dry-run|--sim|--cycles]');
  process.exit(2);
}
const endTolerance = 0.005;  // mm: the servo's in-position band on --sim; exact on --dry-run
const modules = path.join(cncjsDir || '', 'node_modules');
if (!motionctl || !fs.existsSync(path.join(modules, 'cncjs', 'package.json'))) {
  console.error(`cncjs is not installed in ${cncjsDir}: run scripts/deps.sh (it installs cncjs 1.11.5 from npm)`);
  process.exit(1);
}
const io = require(path.join(modules, 'socket.io-client'));
const jwt = require(path.join(modules, 'jsonwebtoken'));

const work = fs.mkdtempSync(path.join(os.tmpdir(), 'mc_cncjs_'));
const link = path.join(work, 'motioncore');
const env = sim ? { ...process.env, XDG_RUNTIME_DIR: work } : process.env;
const t0 = Date.now();
const children = [];
let failed = false;  // set once the run is decided: children's exits no longer count
let dump = () => '';

function finish(code, why) {
  failed = true;
  if (why) console.log(why);
  // Remove the work directory once every child has exited.
  const exited = children.map((c) => (c.exitCode !== null || c.signalCode !== null
    ? Promise.resolve()
    : new Promise((resolve) => c.once('exit', resolve))));
  for (const c of children) c.kill('SIGTERM');
  Promise.all(exited).then(() => {
    if (sim) require('child_process').spawnSync(motionctl, ['sim', 'stop'], { env });
    fs.rmSync(work, { recursive: true, force: true });
    process.exit(code);
  });
}
function fail(why) {
  if (failed) return;
  finish(1, `FAIL: ${why}\n${dump()}`);
}
// Only a guard: every step below waits on an event from cncjs.
const guardS = mode === '--cycles' ? 400 : 120;
setTimeout(() => fail(`the job did not finish within ${guardS} s`), guardS * 1000).unref();

function freePort() {
  return new Promise((resolve) => {
    const s = net.createServer().listen(0, '127.0.0.1', () => {
      const { port } = s.address();
      s.close(() => resolve(port));
    });
  });
}

// Waits for `proc` to print a line matching `re` on stdout.
function waitOutput(proc, re, what) {
  return new Promise((resolve) => {
    let text = '';
    proc.stdout.on('data', (d) => {
      text += d.toString();
      if (re.test(text)) resolve(text);
    });
    proc.on('exit', (code) => fail(`${what} exited (${code}) before it was ready:\n${text}`));
  });
}

// The job: lines, arcs, 200 short segments (character counting under load),
// ending at X12.5 Y7.5 Z0.
function job() {
  // On --sim, faster feeds and fewer zig-zags: the virtual board runs in real time.
  const [slow, zigzags] = mode === '--sim' ? [2400, 20] : [600, 200];
  const l = ['G21 G90 G94', 'G0 X0 Y0 Z0', `G1 X20 F${slow}`, 'G2 X30 Y10 I0 J10', 'G1 Y30', 'G3 X20 Y40 I-10 J0'];
  for (let i = 0; i < zigzags; ++i) l.push(`G1 X${(20 - 0.1 * (i + 1)).toFixed(1)} Y${i % 2 ? 40 : 39.5} F3000`);
  l.push(`G1 X0 Y40 F${2 * slow}`, 'G1 Y0', 'G0 X12.5 Y7.5');
  return l.join('\n') + '\n';
}

async function main() {
  // --sim: the virtual board is paced to the wall clock and catches up after
  // the OS has descheduled it, which a loaded machine does for longer than the
  // board's 100 ms watchdog: give it a second.
  const machine = sim ? ['--sim', 'serve', '--watchdog', '1s'] : ['serve', '--dry-run'];
  if (mode === '--cycles') machine.push('--level', await mapTheBed());
  const serve = spawn(motionctl, [...machine, '--pty', link, '--settings', path.join(work, 'grbl.toml')], { env });
  children.push(serve);
  serve.stderr.on('data', (d) => process.stderr.write(`serve: ${d}`));
  await waitOutput(serve, /Ctrl-C stops/, 'motionctl serve');

  const secret = 'motioncore-test-secret';
  const config = path.join(work, 'cncrc.json');
  fs.writeFileSync(config, JSON.stringify({
    secret,
    ports: [{ path: link, manufacturer: 'MotionCore' }],
    state: { checkForUpdates: false, allowAnonymousUsageDataCollection: false },
  }));
  const port = await freePort();
  const cncjs = spawn(process.execPath, [path.join(modules, 'cncjs', 'bin', 'cncjs'), '--host', '127.0.0.1',
    '--port', String(port), '--config', config], { env: { ...process.env, HOME: work } });
  children.push(cncjs);
  cncjs.stderr.on('data', (d) => process.stderr.write(`cncjs: ${d}`));
  cncjs.stdout.on('data', () => {});
  cncjs.on('exit', (code) => fail(`cncjs exited (${code})`));

  // socket.io retries until cncjs listens.
  const token = jwt.sign({ id: '', name: 'motioncore-test' }, secret, { expiresIn: '1h' });
  const socket = io.connect(`ws://127.0.0.1:${port}`, { query: `token=${token}` });
  socket.on('error', (e) => fail(`socket.io: ${e}`));

  let state = {};        // the last Grbl status cncjs parsed
  let sender = {};       // the last sender status
  let workflow = '';
  const reads = [];      // every line cncjs read from the port
  const waiters = [];
  dump = () => `workflow ${workflow}, state ${JSON.stringify(state)}, sender ${JSON.stringify(sender)}, ` +
    `last lines read: ${JSON.stringify(reads.slice(-12))}`;
  const check = () => {
    for (let i = waiters.length; i-- > 0;) {
      if (waiters[i].pred()) waiters.splice(i, 1)[0].resolve();
    }
  };
  const until = (pred) => new Promise((resolve) => { waiters.push({ pred, resolve }); check(); });
  socket.on('controller:state', (type, s) => {
    state = (s && s.status) || {};
    check();
  });
  socket.on('sender:status', (s) => { sender = s; check(); });
  socket.on('workflow:state', (w) => { workflow = w; check(); });
  socket.on('serialport:write', (d) => { if (process.env.MC_DEBUG) console.log('write', JSON.stringify(d)); });
  socket.on('serialport:read', (line) => {
    if (process.env.MC_DEBUG) console.log('read', JSON.stringify(line));
    reads.push(line);
    if (/^(error|ALARM)/.test(line)) fail(`the server answered "${line}"`);
    check();
  });

  await new Promise((resolve) => socket.on('connect', resolve));
  await new Promise((resolve) => socket.emit('open', link, { controllerType: 'Grbl', baudrate: 115200 }, (err) => {
    if (err) fail(`cncjs could not open ${link}: ${err}`);
    resolve();
  }));
  await until(() => state.activeState === 'Idle');
  console.log(`cncjs opened ${link}: Idle`);
  if (mode === '--cycles') {
    await cycles(socket, until, { reads: () => reads, state: () => state, workflow: () => workflow, sender: () => sender });
    return;
  }

  const text = job();
  const lines = text.trim().split('\n').length;
  await new Promise((resolve) => socket.emit('command', link, 'gcode:load', 'job.nc', text, {}, (err) => {
    if (err) fail(`gcode:load: ${err}`);
    resolve();
  }));
  socket.emit('command', link, 'gcode:start');
  await until(() => workflow === 'running' && state.activeState === 'Run');
  console.log(`running ${lines} lines (+ cncjs's closing %wait)`);

  // A feed hold in the middle: Hold:0 and standing still, then resume.
  await until(() => sender.received > 10);
  socket.emit('command', link, 'feedhold');
  await until(() => state.activeState === 'Hold' && state.subState === 0);
  // Standing still: four more reports asked for through cncjs show the same position.
  const report = async () => {
    const n = reads.length;
    socket.emit('write', link, '?');
    await until(() => reads.slice(n).some((r) => r.startsWith('<')));
    return reads.slice(n).find((r) => r.startsWith('<'));
  };
  const mpos = (r) => (/MPos:([^|>]*)/.exec(r) || [])[1];
  const held = mpos(await report());
  for (let i = 0; i < 4; ++i) {
    const r = await report();
    // Standing still: within the servo's in-position band on --sim (exact on --dry-run).
    const moved = mpos(r).split(',').some((v, k) => Math.abs(Number(v) - Number(held.split(',')[k])) > endTolerance);
    if (!r.startsWith('<Hold:0|') || moved) {
      fail(`moved while held: MPos ${held} -> ${r}`);
      return;
    }
  }
  console.log(`held at MPos ${held} after ${sender.received} lines acknowledged`);
  socket.emit('command', link, 'cyclestart');
  await until(() => state.activeState === 'Run');

  // Feed override +10 %: the report shows it.
  socket.emit('command', link, 'feedOverride', 10);
  await until(() => state.ov && Number(state.ov[0]) === 110);
  console.log('feed override 110 %');

  await until(() => workflow === 'idle' && sender.total > 0 && sender.received === sender.total &&
    state.activeState === 'Idle');
  const end = state.mpos;
  console.log(`done: ${sender.received}/${sender.total} lines acknowledged, machine at ${JSON.stringify(end)}`);
  const off = (v, want) => Math.abs(Number(v) - want) > endTolerance;
  if (off(end.x, 12.5) || off(end.y, 7.5) || off(end.z, 0)) {
    fail(`the machine ended at ${JSON.stringify(end)}, not at X12.5 Y7.5 Z0`);
    return;
  }
  finish(0, `PASS: cncjs ran the job to its end on motionctl serve ${mode} in ${((Date.now() - t0) / 1000).toFixed(1)} s`);
}

// --cycles: home, then probe the bed's map with the CLI, before serving.
const bedMap = path.join(work, 'bed.toml');
const area = [20, 20, 100, 80];  // X0, Y0, X1, Y1 (mm): a 3 x 2 grid
async function mapTheBed() {
  const { spawnSync } = require('child_process');
  for (const args of [['--sim', 'home'], ['--sim', 'level', 'probe', '--grid', '3x2', '--area', area.join(','), '-o', bedMap]]) {
    const r = spawnSync(motionctl, args, { env, encoding: 'utf8' });
    if (r.status !== 0) throw new Error(`motionctl ${args.join(' ')} failed (${r.status}):\n${r.stdout}${r.stderr}`);
    console.log(`motionctl ${args.join(' ')}: ${r.stdout.trim().split('\n').slice(-2).join(' / ')}`);
  }
  return bedMap;
}

async function cycles(socket, until, { reads, state, workflow, sender }) {
  const lastRead = (re, from) => reads().slice(from).find((l) => re.test(l));
  // Every line of `text` answered `ok`, then Idle (reported once the servos settled).
  const gcode = async (text) => {
    const n = reads().length;
    const count = text.trim().split('\n').length;
    socket.emit('command', link, 'gcode', text);
    await until(() => reads().slice(n).filter((l) => l === 'ok').length >= count);
    await new Promise((resolve) => setTimeout(resolve, 600));  // cncjs polls `?` every 250 ms
    await until(() => state().activeState === 'Idle');
    return n;
  };
  // Homing: $22=1, then cncjs's homing command ($H); Home while it runs.
  await gcode('$22=1');
  socket.emit('command', link, 'homing');
  await until(() => state().activeState === 'Home');
  await until(() => state().activeState === 'Idle');
  console.log(`homed: MPos ${JSON.stringify(state().mpos)}`);
  // Touch off on the map's first point, as cncjs's probe widget does.
  const from = await gcode(`G90 G0 X${area[0]} Y${area[1]}\nG91\nG38.2 Z-20 F300\nG90\nG10 L20 P1 Z0\nG91\nG0 Z2\nG90`);
  const prb = lastRead(/^\[PRB:/, from);
  if (!prb || !/:1\]$/.test(prb)) throw new Error(`no probe contact: ${prb}`);
  console.log(`probed: ${prb}`);
  // The map's grid point that lies furthest from the first point's height.
  const rows = /heights_mm = \[([\s\S]*)\]/.exec(fs.readFileSync(bedMap, 'utf8'))[1].trim().split('\n')
    .map((r) => r.replace(/[[\]\s]/g, '').split(',').filter((v) => v !== '').map(Number));
  let end = { i: 0, j: 0, h: 0 };
  rows.forEach((r, j) => r.forEach((h, i) => { if (Math.abs(h) > Math.abs(end.h)) end = { i, j, h }; }));
  const ex = area[0] + end.i * (area[2] - area[0]) / (rows[0].length - 1);
  const ey = area[1] + end.j * (area[3] - area[1]) / (rows.length - 1);
  const h = end.h;
  // The engraving, in work coordinates: down 0.1 mm at the first point, cuts
  // along X and Y to the map's far corner, then to that point, staying there
  // at depth.
  const job = `G21 G90 G54\nG0 X${area[0]} Y${area[1]} Z1\nG1 Z-0.1 F300\nG1 X${area[2]} F1500\nG1 Y${area[3]}\n` +
    `G1 X${ex} Y${ey}\n`;
  await new Promise((resolve) => socket.emit('command', link, 'gcode:load', 'engrave.nc', job, {}, resolve));
  socket.emit('command', link, 'gcode:start');
  await until(() => workflow() === 'running');
  await until(() => workflow() === 'idle' && sender().total > 0 && sender().received === sender().total &&
    state().activeState === 'Idle');
  await new Promise((resolve) => setTimeout(resolve, 600));
  const w = state().wpos;
  const want = -0.1 + h;
  console.log(`engraved: ended at X${ex} Y${ey}, the map's height there ${h} mm, work Z ${w.z} (want ${want.toFixed(4)})`);
  if (Math.abs(h) < 0.05) throw new Error(`the map (${JSON.stringify(rows)}) is too flat to show levelling`);
  if (Math.abs(Number(w.z) - want) > endTolerance || Math.abs(Number(w.x) - ex) > endTolerance ||
      Math.abs(Number(w.y) - ey) > endTolerance) {
    throw new Error(`the job ended at work ${JSON.stringify(w)}, not X${ex} Y${ey} Z${want.toFixed(4)}`);
  }
  finish(0, `PASS: cncjs homed, probed and ran a levelled job on motionctl --sim serve --level in ${((Date.now() - t0) / 1000).toFixed(1)} s`);
}

main().catch((e) => fail(e.stack || String(e)));
