// Browser tests of tridex's --html page (issue 15), in Debian's headless Chromium driven by
// puppeteer-core: the page loads with no console error and no network request, the part is drawn
// (pixels of its colour where it is, none when it is hidden), choosing a finding flies the camera
// to it and lists its G-code lines (a holder collision in a subprogram file: that file's line),
// the slider changes the drawn toolpath (in program order, through the subprogram), and pages for an empty
// result and a program without moves say so. Issue 32: faults on a face the front view does not
// show (a gouge, an excess, a rapid) and a holder collision are each in view once chosen (a ray
// cast here, on its own, from camera().position against the page's result mesh), grouped
// findings, playback (step 0 against the last step: pixels and stock), the tool, play, print on
// one page. Screenshots are kept in OUT_DIR.
//   node report_test.mjs TRIDEX OUT_DIR CHROMIUM      (run by run.sh, CTest's html_report_browser)
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';
import puppeteer from 'puppeteer-core';

const [tridex, out, chromium] = process.argv.slice(2);
const repo = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
let passed = 0, failed = 0;
function check(condition, what) {
  if (condition) ++passed;
  else { ++failed; console.log('FAILED: ' + what); }
}

function run(args, statuses = [0]) {
  const r = spawnSync(tridex, args, { encoding: 'utf8' });
  if (!statuses.includes(r.status)) throw new Error('tridex ' + args.join(' ') + ' exited ' + r.status + ':\n' + r.stderr);
  return r;
}
const write = (name, text) => { fs.writeFileSync(path.join(out, name), text); return path.join(out, name); };

// ---- the pages ---------------------------------------------------------------------------------
// The bundled example (coarse, to keep the test quick).
const examplePage = path.join(out, 'example.html');
run(['simulate', path.join(repo, 'gcode/examples/mold_3plus2.camotics'), '--dexel-res', '128', '-q',
     '--report', path.join(out, 'example.json'), '--html', examplePage]);
// check's planted faults (tests/tools/test_check.cpp): a plunge 0.3 mm too deep in a tilted
// direction (line 13) against the correct program's result, and an envelope the rapids leave.
const tools = write('tools.json', '{"1": {"units": "mm", "shape": "cylindrical", "diameter": 6, "length": 20}}');
const program = (z) => '%\nG21 G17 G90\nT1 M6\nS8000 M3\nG68.2 X10 Y10 Z10 I0 J20 K0\nG53.1\n' +
  'G0 X-3 Y0\nG0 Z5\nG1 Z-1 F500\nG1 X3\nG0 Z5\nG0 X0 Y4\nG1 Z' + z + '\nG0 Z5\nG28 G91 Z0.\nG69\nM30\n%\n';
const stock = ['--tools', tools, '--stock', 'box:0,0,0,20,20,10', '--dexel-cell', '0.1', '-q'];
run(['simulate', write('good.nc', program(-2)), ...stock, '-o', path.join(out, 'design.stl')]);
const checkPage = path.join(out, 'check.html');
run(['check', write('gouge.nc', program(-2.3)), ...stock, '--design', path.join(out, 'design.stl'), '--tolerance', '0.1',
     '--envelope', 'box:-1,-1,-1,21,21,14', '--report', path.join(out, 'check.json'), '--html', checkPage], [3]);
// diff (issue 39): the plunge 0.3 mm too deep against the correct program: one region B removed,
// listed with its line in B (13), B's surface as the part and A's as the ghost.
const diffPage = path.join(out, 'diff.html');
run(['diff', path.join(out, 'good.nc'), write('deep.nc', program(-2.3)), ...stock, '--tolerance', '0.1',
     '--report', path.join(out, 'diff.json'), '--html', diffPage], [3]);
// A holder that hits, in a subprogram file (M98 P1002 finds O1002.nc beside the program): a hole
// 25 mm deep 4 mm from the front face buries the Ø30 holder 20 mm out (tests/tools/test_collisions.cpp)
// at the subprogram's line 3; the main program's line 3 moves too (its listing must not be marked).
const holderTools = write('holder_tools.json', '{"1": {"shape": "cylindrical", "diameter": 6, "stick-out": 20, ' +
                          '"holder": [{"bottom-diameter": 30, "top-diameter": 30, "length": 20}]}}');
write('O1002.nc', 'O1002\nG0 X30 Y4 Z40\nG1 Z5 F300\nG0 Z40\nM99\n');
const holderProgram = write('holder.nc', '%\nG21 G17 G90 T1 M6\nS8000 M3 G0 X30 Y4 Z40\nM98 P1002\nG0 X50 Y30 Z40\n' +
                            'G1 Z28 F300\nG0 Z40\nM30\n%\n');
const holderArgs = ['--tools', holderTools, '--stock', 'box:0,0,0,60,40,30', '--dexel-cell', '0.5', '-q'];
run(['simulate', holderProgram, ...holderArgs, '-o', path.join(out, 'holder_design.stl')]);
const holderPage = path.join(out, 'holder.html');
run(['check', holderProgram, ...holderArgs, '--design', path.join(out, 'holder_design.stl'), '--tolerance', '0.6',
     '--report', path.join(out, 'holder.json'), '--html', holderPage], [3]);
// Faults on the +Y face, which the default (iso, from the front right) view does not show
// (issue 32): the spindle along +Y (G68.2 I180 J90: the plane's X is world −X, its Y world +Z),
// a slot and a plunge 0.3 mm too deep (the gouge), a hole the design has and the program lacks (the
// excess) and a rapid plunge into the face that both make (the rapid cut).
const faceProgram = (z, extra) => '%\nG21 G17 G90\nT1 M6\nS8000 M3\nG68.2 X10 Y20 Z5 I180 J90 K0\nG53.1\n' +
  'G0 X-3 Y0\nG0 Z5\nG1 Z-1 F500\nG1 X3\nG0 Z5\nG0 X0 Y2\nG1 Z' + z + '\nG0 Z5\nG0 X6 Y-2\nG0 Z-0.5\nG0 Z5\n' + extra +
  'G28 G91 Z0.\nG69\nM30\n%\n';
run(['simulate', write('face_good.nc', faceProgram(-2, 'G0 X-5 Y-3\nG1 Z-1.5\nG0 Z5\n')), ...stock, '-o', path.join(out, 'face_design.stl')]);
const facePage = path.join(out, 'face.html');
run(['check', write('face.nc', faceProgram(-2.3, '')), ...stock, '--design', path.join(out, 'face_design.stl'), '--tolerance', '0.1',
     '--report', path.join(out, 'face.json'), '--html', facePage], [3]);
// A program over the page's 4 MiB of plain text (40,000 short moves, each line with a long comment,
// as some posts write): its text goes compressed in chunks of lines, and the slider still shows the
// text of any line. (Few, short moves: the page's playback cells cost moves × cells they cross.)
const largeLines = ['%', 'G21 G17 G90', 'T1 M6', 'S8000 M3', 'G0 X10 Y10 Z5', 'G1 Z-0.5 F900'];
for (let k = 0; k < 40000; ++k)
  largeLines.push('G1 X' + (k % 2 ? 11 : 10).toFixed(3) + ' Y' + (10 + 0.002 * k).toFixed(4) + ' Z-0.5 (pass ' + k +
                  ' of 40000: ' + 'a comment a post writes on every line, '.repeat(2) + ')');
largeLines.push('G0 Z5', 'M30', '%');
const largeProgram = write('large.nc', largeLines.join('\n') + '\n');
const largePage = path.join(out, 'large.html');
run(['simulate', largeProgram, '--tools', tools, '--stock', 'box:0,0,-5,100,100,0', '--dexel-cell', '1', '-q', '--html', largePage]);
// Nothing left: a cutter wider than the stock plunges through it. No moves: a program of words only.
const emptyPage = path.join(out, 'empty.html');
run(['simulate', write('through.nc', '%\nG21 G90\nT1 M6\nM3 S1000\nG0 X5 Y5 Z20\nG1 Z-20 F100\nG0 Z20\nM30\n%\n'),
     '--tools', write('big.json', '{"1": {"units": "mm", "shape": "cylindrical", "diameter": 60, "length": 50}}'),
     '--stock', 'box:0,0,0,10,10,10', '-q', '--html', emptyPage]);
const noMovesPage = path.join(out, 'no_moves.html');
run(['simulate', write('nothing.nc', '%\nG21 G90\nM30\n%\n'), '--stock', 'box:0,0,0,10,10,10', '-q', '--html', noMovesPage]);

// The machine check (issue 33): a clamp beside the stock and a spindle nose (Ø80, on the spindle,
// 60 mm above the tip with the tool's length) that comes down onto the clamp's top while the tool
// plunges beside it (line 5, as tests/tools/test_machine_check.cpp's bar). Without a tool length
// the nose cannot be placed: the page says so by the verdict.
const boxFacets = (lo, hi) => {
  const v = (i) => [i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]];
  return [[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4], [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]]
    .map((t) => t.map(v));
};
const prismFacets = (r, h, sides) => {
  const at = (k, z) => [r * Math.cos(2 * Math.PI * k / sides), r * Math.sin(2 * Math.PI * k / sides), z], out = [];
  for (let k = 0; k < sides; ++k) {
    out.push([at(k, 0), at(k + 1, 0), at(k + 1, h)], [at(k, 0), at(k + 1, h), at(k, h)]);
    out.push([[0, 0, 0], at(k + 1, 0), at(k, 0)], [[0, 0, h], at(k, h), at(k + 1, h)]);
  }
  return out;
};
const stl = (name, facets) => write(name, 'solid s\n' + facets.map((t) => ' facet normal 0 0 0\n  outer loop\n' +
  t.map((p) => '   vertex ' + p.join(' ') + '\n').join('') + '  endloop\n endfacet\n').join('') + 'endsolid s\n');
const clamp = stl('clamp.stl', boxFacets([110, 20, -30], [130, 40, 45]));
stl('nose.stl', prismFacets(40, 80, 24));
const machineFile = write('machine_file.json', '{"components": [{"name": "spindle nose", "on": "spindle", "mesh": "nose.stl"}], ' +
                          '"collision": {"clearance": 0.5, "near_miss": 2}}');
const machineProgram = write('machine.nc', 'G21 G90 G17\nT1 M6\nG43 H1\nG0 X85 Y30 Z50\nG1 Z-25 F300\nG0 Z50\nM30\n');
const machineArgs = (tool) => ['--tools', write('machine_tools.json', '{"1": {"shape": "cylindrical", "diameter": 6, "length": 35' + tool + '}}'),
                               '--stock', 'box:0,0,-30,100,60,0', '--dexel-cell', '1', '-q'];
run(['simulate', machineProgram, ...machineArgs(', "tool-length": 60'), '-o', path.join(out, 'machine_design.stl')]);
const machinePage = path.join(out, 'machine.html');
run(['check', machineProgram, ...machineArgs(', "tool-length": 60'), '--design', path.join(out, 'machine_design.stl'), '--tolerance', '1',
     '--machine', machineFile, '--fixture', clamp, '--report', path.join(out, 'machine_report.json'), '--html', machinePage], [3]);
const unplacedPage = path.join(out, 'unplaced.html');
run(['check', machineProgram, ...machineArgs(''), '--design', path.join(out, 'machine_design.stl'), '--tolerance', '1',
     '--machine', machineFile, '--fixture', clamp, '--report', path.join(out, 'unplaced.json'), '--html', unplacedPage], [0, 3]);
// Five spindle directions (as the bundled example has): the toolbar wraps to a second row at
// 1280 × 800, where the deviation legend once covered the clipping plane's "flip".
const planes = [[0, 20], [90, 20], [180, 20], [-90, 20], [45, 30]];
const manyProgram = '%\nG21 G17 G90\nT1 M6\nS8000 M3\n' + planes.map(([i, j], k) => 'G68.2 X10 Y10 Z10 I' + i + ' J' + j + ' K0\nG53.1\n' +
  'G0 X' + (k - 2) * 3 + ' Y0\nG0 Z5\nG1 Z-0.5 F500\nG0 Z5\nG69\n').join('') + 'M30\n%\n';
write('many.nc', manyProgram);
const coarse = ['--tools', tools, '--stock', 'box:0,0,0,20,20,10', '--dexel-cell', '0.25', '-q'];  // the layout is the subject
run(['simulate', path.join(out, 'many.nc'), ...coarse, '-o', path.join(out, 'many_design.stl')]);
const manyPage = path.join(out, 'many.html');
run(['check', path.join(out, 'many.nc'), ...coarse, '--design', path.join(out, 'many_design.stl'), '--tolerance', '0.5', '--html', manyPage], [0, 3]);

// ---- the browser ---------------------------------------------------------------------------------
const profile = fs.mkdtempSync(path.join(out, 'profile-'));
const browser = await puppeteer.launch({
  executablePath: chromium,
  headless: true,
  userDataDir: profile,
  args: ['--headless=new', '--no-sandbox', '--disable-gpu', '--enable-unsafe-swiftshader', '--use-angle=swiftshader',
         '--disable-background-networking', '--disable-component-update', '--no-first-run'],
});

// Opens a page; returns it with the console errors and requests it made, and its load time.
async function open(file) {
  const page = await browser.newPage();
  await page.setViewport({ width: 1280, height: 800 });
  const errors = [], requests = [];
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('request', (r) => requests.push(r.url()));
  const url = pathToFileURL(file).href, start = performance.now();
  await page.goto(url, { waitUntil: 'load', timeout: 120000 });
  await page.waitForFunction('window.tridexView && window.tridexView.ready', { timeout: 120000 });
  const seconds = (performance.now() - start) / 1000;
  console.log(path.basename(file) + ': ' + (fs.statSync(file).size / 1e6).toFixed(2) + ' MB, ready in ' + seconds.toFixed(2) + ' s');
  const name = path.basename(file);
  return { page, errors, seconds,
           clean() { check(errors.length === 0, name + ': console errors: ' + errors.join(' | '));
                     const network = requests.filter((r) => !r.startsWith('data:'));
                     check(network.length === 1 && network[0] === url, name + ': requests other than the page: ' + requests.join(' ')); } };
}
// The visibility the bar asks for, done here on its own: from camera().position, a ray
// to the point against the page's result mesh (Möller–Trumbore over every triangle) meets no
// triangle before it (within 1e-3 of the part's diagonal), and the point lies in front.
function resultMesh(data) {
  const q = new Uint16Array(Buffer.from(data.mesh.positions, 'base64').buffer.slice(0));
  const raw = Buffer.from(data.mesh.indices, 'base64'), indices = new Uint32Array(raw.buffer.slice(raw.byteOffset, raw.byteOffset + raw.length));
  const b = data.mesh.box, points = [];
  for (let i = 0; i < q.length; ++i) points.push(b.min[i % 3] + (q[i] / 65535) * (b.max[i % 3] - b.min[i % 3]));
  return { points, indices, diagonal: Math.hypot(...b.min.map((x, a) => b.max[a] - x)) };
}
function visible(mesh, from, target, point) {
  const sub = (a, b) => a.map((x, i) => x - b[i]), dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const to = sub(point, from), length = Math.hypot(...to), d = to.map((x) => x / length);
  if (dot(sub(target, from), to) <= 0) return { visible: false, why: 'behind the camera' };
  const p = mesh.points, limit = length - 1e-3 * mesh.diagonal;
  for (let t = 0; t < mesh.indices.length; t += 3) {
    const v = [0, 1, 2].map((k) => p.slice(3 * mesh.indices[t + k], 3 * mesh.indices[t + k] + 3));
    const e1 = sub(v[1], v[0]), e2 = sub(v[2], v[0]), h = cross(d, e2), a = dot(e1, h);
    if (Math.abs(a) < 1e-12) continue;
    const s = sub(from, v[0]), u = dot(s, h) / a;
    if (u < 0 || u > 1) continue;
    const qq = cross(s, e1), w = dot(d, qq) / a;
    if (w < 0 || u + w > 1) continue;
    const distance = dot(e2, qq) / a;
    if (distance > 0 && distance < limit) return { visible: false, why: 'hidden at ' + distance.toFixed(4) + ' of ' + length.toFixed(4) };
  }
  return { visible: true };
}
const pointOf = (kind, f) => (kind === 'rapid_cuts' ? f.where : kind === 'collisions' ? f.point : f.deepest_point);
// Chooses each finding of `kinds` by its data-finding and checks the point is in view (not hidden,
// in front of the camera), and that the slider went to its line; a screenshot of each.
async function checkInView(page, name, report, data, kinds, hiddenBefore) {
  const mesh = resultMesh(data);
  if (hiddenBefore) {  // the faults are where the front view does not show them
    await toggle(page, 'views button:nth-child(2)');
    await settle(page);
    const before = await view(page, 'camera');
    for (const kind of kinds)
      for (const [k, f] of report[kind].entries())
        check(!visible(mesh, before.position, before.target, pointOf(kind, f)).visible, name + ': ' + kind + ':' + k + ' is hidden from the front');
  }
  for (const kind of kinds) {
    check(report[kind].length > 0, name + ': the report has ' + kind);
    for (const [k, f] of report[kind].entries()) {
      const point = pointOf(kind, f);
      // A grouped finding's own row (data-member) when it is not the first of its group.
      if (await page.$('[data-finding="' + kind + ':' + k + '"]')) await page.click('[data-finding="' + kind + ':' + k + '"]');
      else await page.$eval('[data-member="' + kind + ':' + k + '"]', (e) => { e.hidden = false; e.click(); });
      const cam = await view(page, 'camera'), seen = visible(mesh, cam.position, cam.target, point);
      check(seen.visible, name + ': ' + kind + ':' + k + ' in view after it is chosen: ' + seen.why + ' ' + JSON.stringify(cam));
      const onScreen = await view(page, 'project', point);
      check(Math.abs(onScreen[0]) < 0.9 && Math.abs(onScreen[1]) < 0.9 && onScreen[2] < 1, name + ': ' + kind + ':' + k + ' on screen: ' + onScreen);
      const line = f.line !== undefined ? f.line : (f.lines || [])[0];
      if (line !== undefined) {
        const label = await page.$eval('#path-label', (e) => e.textContent);
        check(new RegExp('up to (line |[^ ]*:)' + line + ' ').test(label), name + ': ' + kind + ':' + k + ' sets the slider to line ' + line + ': ' + label);
      }
      await page.screenshot({ path: path.join(out, name + '_' + kind + '_' + k + '.png') });
    }
  }
}
// The view's pixels at step 0 and the last step (toolpath and rapids hidden): the fraction that
// differ, and the stock's pixels at each.
async function playbackDiff(page) {
  return page.evaluate(async () => {
    const v = window.tridexView, canvas = document.querySelector('#view canvas');
    const grab = () => { const c = document.createElement('canvas'); c.width = canvas.width; c.height = canvas.height;
                         const g = c.getContext('2d'); g.drawImage(canvas, 0, 0); return g.getImageData(0, 0, c.width, c.height).data; };
    await v.layer('toolpath', false); await v.layer('rapids', false);
    await v.step(0);
    const first = grab(), stockFirst = v.sample().stock;
    await v.step(Math.floor(v.steps() / 2));
    const stockHalf = v.sample().stock;
    await v.step(v.steps() - 1);
    const last = grab(), stockLast = v.sample().stock;
    let differ = 0;
    for (let i = 0; i < first.length; i += 4)
      if (Math.abs(first[i] - last[i]) + Math.abs(first[i + 1] - last[i + 1]) + Math.abs(first[i + 2] - last[i + 2]) > 24) ++differ;
    return { fraction: differ / (first.length / 4), stockFirst, stockHalf, stockLast };
  });
}
const settle = (page) => page.waitForFunction('!window.tridexView.flying', { timeout: 30000 });
const toggle = (page, id) => page.$eval('#' + id, (e) => e.click());
// A finding chosen by a DOM click: a mouse click at the entry's centre can land on its neighbour
// when the list's layout shifts under a loaded machine (the contract test above clicks as a user).
const chooseFinding = (page, key) => page.$eval('#findings li[data-finding="' + key + '"]', (e) => e.click());
async function setSlider(page, value) {
  await page.$eval('#path-slider', (e, v) => { e.value = String(v === 'max' ? e.max : v); e.dispatchEvent(new Event('input')); }, value);
}
const pageData = (page) => page.$eval('#tridex-data', (e) => JSON.parse(e.textContent));
const view = (page, call, ...args) => page.evaluate((c, a) => window.tridexView[c](...a), call, args);
const near = (a, b, tolerance) => a.every((x, i) => Math.abs(x - b[i]) <= tolerance);
async function setClip(page, axis, at, flip) {
  await page.$eval('#clip-axis', (e, v) => { e.value = v; e.dispatchEvent(new Event('input')); }, axis);
  await page.$eval('#clip-flip', (e, v) => { e.checked = v; e.dispatchEvent(new Event('input')); }, flip);
  await page.$eval('#clip-at', (e, v) => { e.value = String(v); e.dispatchEvent(new Event('input')); }, at);
}

try {
  // The bundled example: the part where it is, the toolpath's slider.
  {
    const { page, clean } = await open(examplePage);
    const data = await pageData(page);
    check(JSON.stringify(data.report) === JSON.stringify(JSON.parse(fs.readFileSync(path.join(out, 'example.json')))),
          'example: the page holds the report');
    check(data.directions.length === data.report.groups.length, 'example: one preset view per direction');
    check((await page.$$('#presets button')).length === data.report.groups.length, 'example: preset buttons');
    await page.screenshot({ path: path.join(out, 'example.png') });
    await toggle(page, 'show-path'); await toggle(page, 'show-rapids');
    const [cx, cy] = await page.evaluate(() => window.tridexView.project(window.tridexView.centre));
    const around = await page.evaluate((x, y) => window.tridexView.sample(x - 0.1, y - 0.1, x + 0.1, y + 0.1), cx, cy);
    check(around.part > 0.8 * around.all, 'example: part-coloured pixels around the part centre: ' + JSON.stringify(around));
    const whole = await page.evaluate(() => window.tridexView.sample());
    check(whole.part > 0.05 * whole.all && whole.background > 0.05 * whole.all, 'example: part and background on screen: ' + JSON.stringify(whole));
    await toggle(page, 'show-part');
    const hidden = await page.evaluate(() => window.tridexView.sample());
    check(hidden.part < 0.001 * hidden.all, 'example: no part-coloured pixels with the part hidden: ' + JSON.stringify(hidden));
    // The slider: the whole program, then its first line with moves only.
    await toggle(page, 'show-path');
    await setSlider(page, 'max');
    const full = await page.evaluate(() => [window.tridexView.drawnSegments(), window.tridexView.sample().checksum]);
    await setSlider(page, 0);
    const first = await page.evaluate(() => [window.tridexView.drawnSegments(), window.tridexView.sample().checksum]);
    check(full[0] === data.toolpath.segments && first[0] < full[0] / 10, 'example: slider segments ' + first[0] + ' of ' + full[0]);
    check(full[1] !== first[1], 'example: the slider changes the drawn path');
    await setSlider(page, Math.floor((await page.$eval('#path-slider', (e) => Number(e.max))) / 2));
    await page.screenshot({ path: path.join(out, 'example_path_half.png') });
    // Rapids and feeds apart, colour by tool or by direction: each changes the drawn path.
    await setSlider(page, 'max');
    const withRapids = (await view(page, 'sample')).checksum;
    await toggle(page, 'show-rapids');
    check((await view(page, 'sample')).checksum !== withRapids, 'example: the rapids checkbox changes the drawn path');
    await toggle(page, 'show-rapids');
    await page.select('#path-colour', 'direction');
    check((await view(page, 'sample')).checksum !== withRapids, 'example: colouring by direction changes the drawn path');
    await page.select('#path-colour', 'tool');
    check((await view(page, 'sample')).checksum === withRapids, 'example: colouring by tool again restores it');
    await toggle(page, 'show-path'); await toggle(page, 'show-rapids'); await toggle(page, 'show-part');
    // The mouse: drag to orbit, wheel to zoom, right-drag to pan; Fit brings the whole part back.
    const box = await (await page.$('#view')).boundingBox(), mx = box.x + box.width / 2, my = box.y + box.height / 2;
    const fitted = [await view(page, 'viewDirection'), await view(page, 'distance'), await view(page, 'project', data.mesh.box.min)];
    check(near((await view(page, 'project', await page.evaluate(() => window.tridexView.centre))).slice(0, 2), [0, 0], 1e-6),
          'example: fitted on the part centre');
    await page.mouse.move(mx, my); await page.mouse.down(); await page.mouse.move(mx + 150, my + 40, { steps: 5 }); await page.mouse.up();
    const orbited = await view(page, 'viewDirection');
    check(!near(orbited, fitted[0], 0.05), 'example: a drag orbits: ' + [fitted[0], orbited]);
    for (let k = 0; k < 5; ++k) await page.mouse.wheel({ deltaY: -100 });
    const zoomed = await view(page, 'distance');
    check(zoomed < 0.9 * fitted[1], 'example: the wheel zooms in: ' + [fitted[1], zoomed]);
    const beforePan = await view(page, 'project', data.mesh.box.min);
    await page.mouse.move(mx, my); await page.mouse.down({ button: 'right' }); await page.mouse.move(mx - 120, my, { steps: 5 });
    await page.mouse.up({ button: 'right' });
    const panned = await view(page, 'project', data.mesh.box.min);
    check(near(await view(page, 'viewDirection'), orbited, 1e-6) && panned[0] < beforePan[0] - 0.1,
          'example: a right-drag pans: ' + [beforePan, panned]);
    await toggle(page, 'fit');
    await settle(page);
    check(near(await view(page, 'viewDirection'), fitted[0], 1e-6) && Math.abs(await view(page, 'distance') - fitted[1]) < 1e-6 * fitted[1],
          'example: Fit restores the fitted view');
    // A preset view per spindle direction: the camera looks along it, from the holder's side.
    const presets = await page.$$('#presets button');
    for (const [i, g] of data.directions.entries()) {
      await presets[i].click();
      await settle(page);
      const d = await view(page, 'viewDirection'), dot = d.reduce((sum, x, a) => sum + x * g.axis[a], 0);
      check(dot > 0.9999, 'example: preset ' + (i + 1) + ' looks along ' + g.axis + ': ' + d);
    }
    // The clipping plane along Z: flipped, it keeps what lies above it (all of the part at the
    // bottom, none at the top); else what lies below (the part seen cut open in the middle: its
    // inside faces show, so the pixels change but need not be fewer).
    await toggle(page, 'fit');
    await settle(page);
    const unclipped = await view(page, 'sample');
    const clipped = [];
    for (const flip of [false, true])
      for (const at of [0, 500, 1000]) { await setClip(page, '2', at, flip); clipped.push(await view(page, 'sample')); }
    await setClip(page, '2', 500, false);
    await page.screenshot({ path: path.join(out, 'example_clip.png') });
    await setClip(page, '', 500, false);
    check((await view(page, 'sample')).checksum === unclipped.checksum, 'example: no clipping draws the whole part again');
    const [, middle, high, flipLow, flipMiddle, flipHigh] = clipped.map((c) => c.part / unclipped.part);
    check(flipLow > 0.98 && flipHigh < 0.01 && flipMiddle > 0.01 && flipMiddle < 0.99 && high > 0.98 &&
          clipped[1].checksum !== unclipped.checksum && middle > 0.01,
          'example: the clipping plane (Z at 0, ½, 1; flipped): ' + clipped.map((c) => c.part) + ' of ' + unclipped.part);
    clean();
    await page.close();
  }
  // The check: findings listed as in the report; choosing one flies there and lists its lines.
  {
    const { page, clean } = await open(checkPage);
    const report = JSON.parse(fs.readFileSync(path.join(out, 'check.json')));
    const data = await pageData(page);
    check(JSON.stringify(data.report) === JSON.stringify(report), 'check: the page holds the report');
    const expected = report.gouges.length + report.excess.length + report.rapid_cuts.length + report.envelope.violations.length +
                     report.collisions.length + report.near_misses.moves.length +
                     ['missing', 'left'].filter((k) => report.design_side[k].samples > 0).length;
    // Grouped (issue 32): each finding is an entry's data-finding or one of its members'.
    const items = await page.$$eval('#findings li[data-finding]', (l) => l.map((e) => e.textContent));
    const keys = await page.$$eval('#findings li', (l) => [...new Set(l.map((e) => e.dataset.finding || e.dataset.member))]);
    check(keys.length === expected && report.gouges.length === 1 && items.length < expected,
          'check: ' + keys.length + ' findings listed in ' + items.length + ' entries, ' + expected + ' in the report');
    check(items[0].startsWith('gouge') && items[0].includes('mm deep'), 'check: the gouge first: ' + items[0]);
    check(await page.$eval('#legend', (e) => !e.hidden), 'check: the deviation legend is shown');
    // The summary: the report's figures.
    const summary = Object.fromEntries(await page.$$eval('#summary tr', (l) => l.map((r) => [r.cells[0].textContent, r.cells[1].textContent])));
    // In the shop's words: rounded, with units, the time as stdout gives it, the direction by its
    // G68.2 angles, the stock and file names without paths.
    check(summary.verdict === 'fail' && summary.tolerances === '−0.1 / +0.1 mm' &&
          summary['machining time'].startsWith(report.machining_time.total_s.toFixed(1) + ' s (feed ') &&
          summary['volume left'] === (report.result.volume_mm3 / 1000).toFixed(2) + ' cm³' &&
          summary['direction 1'] === 'G68.2 I0 J20 K0: ' + data.directions[0].moves.toLocaleString('en') + ' moves, tools T1' &&
          summary.stock.startsWith('block 20 × 20 × 10 mm') && summary.program === 'gouge.nc' && summary.design === 'design.stl' +
          ' (the design checkbox shows it as a ghost)' && !Object.values(summary).some((v) => v.includes(out)),
          'check: the summary gives the report\'s figures: ' + JSON.stringify(summary));
    const panel = (await page.$eval('#summary', (e) => e.textContent)) + (await page.$eval('#findings', (e) => e.textContent));
    check(!panel.match(/\d\.\d{4}/), 'check: no unrounded numbers in the summary and findings: ' + panel.match(/.{20}\d\.\d{4}.{10}/));
    // The design ghost: off at first, then translucent amber over the part (and over the
    // background where the part is hidden), off again with its checkbox.
    check(await page.$eval('#design-toggle', (e) => !e.hidden) && data.design.triangles_shown > 0, 'check: the design toggle is offered');
    await toggle(page, 'show-path'); await toggle(page, 'show-rapids');
    const noGhost = await page.evaluate(() => window.tridexView.sample());
    await toggle(page, 'show-design');
    const ghost = await page.evaluate(() => window.tridexView.sample());
    await page.screenshot({ path: path.join(out, 'check_design.png') });
    await toggle(page, 'show-part');
    const ghostOnly = await page.evaluate(() => window.tridexView.sample());
    check(noGhost.ghost < 0.001 * noGhost.all && ghost.ghost > 0.05 * ghost.all && ghostOnly.ghost > 0.05 * ghostOnly.all,
          'check: the design ghost is drawn when asked: ' + JSON.stringify([noGhost, ghost, ghostOnly]));
    // Where the design is drawn: its own centre lies on ghost-coloured pixels, part hidden or not.
    const [gx, gy] = await page.evaluate((b) => window.tridexView.project(b.min.map((x, a) => (x + b.max[a]) / 2)), data.design.box);
    const aroundGhost = await page.evaluate((x, y) => window.tridexView.sample(x - 0.05, y - 0.05, x + 0.05, y + 0.05), gx, gy);
    check(aroundGhost.ghost > 0.8 * aroundGhost.all, 'check: ghost pixels around the design centre: ' + JSON.stringify(aroundGhost));
    await toggle(page, 'show-part'); await toggle(page, 'show-design');
    await toggle(page, 'show-path'); await toggle(page, 'show-rapids');
    const point = report.gouges[0].deepest_point;
    const before = await page.evaluate((p) => window.tridexView.project(p), point);
    await chooseFinding(page, 'gouges:0');
    await settle(page);
    const after = await page.evaluate((p) => window.tridexView.project(p), point);
    check(Math.hypot(before[0], before[1]) > 0.05, 'check: the gouge is off the centre before: ' + before);
    check(Math.abs(after[0]) < 0.02 && Math.abs(after[1]) < 0.02 && after[2] > -1 && after[2] < 1,
          'check: the camera flew to the gouge: ' + after);
    const marked = await view(page, 'marked');
    check(marked !== null && near(marked, point, 1e-4), 'check: the gouge is marked: ' + marked);
    // Its deviation colour: red where the gouge is, none on the holder page's part (all within tolerance).
    await toggle(page, 'show-path'); await toggle(page, 'show-rapids');
    const atGouge = await view(page, 'sample', after[0] - 0.5, after[1] - 0.5, after[0] + 0.5, after[1] + 0.5);
    check(atGouge.gouge > 0.02 * atGouge.all, 'check: gouge-red pixels around the gouge: ' + JSON.stringify(atGouge));
    await toggle(page, 'show-path'); await toggle(page, 'show-rapids');
    const listing = await page.$eval('#listing', (e) => e.textContent);
    const hits = await page.$$eval('#listing .hit', (l) => l.map((e) => e.textContent.trim()));
    check(hits.length === 1 && hits[0].startsWith('13') && hits[0].includes('G1 Z-2.3'), 'check: line 13 marked: ' + hits);
    check(listing.includes('G0 X0 Y4') && listing.includes('G0 Z5'), 'check: its neighbouring lines listed');
    await page.screenshot({ path: path.join(out, 'check_gouge.png') });
    // An envelope finding has a point and a line too.
    await chooseFinding(page, 'envelope:0');
    await settle(page);
    const tip = report.envelope.violations[0].tip, seen = await page.evaluate((p) => window.tridexView.project(p), tip);
    check(Math.abs(seen[0]) < 0.02 && Math.abs(seen[1]) < 0.02, 'check: the camera flew to the envelope finding: ' + seen);
    clean();
    await page.close();
  }
  {
    const { page, clean } = await open(diffPage);
    const items = await page.$$eval('#findings li[data-finding]', (l) => l.map((e) => e.textContent));
    check(items.length >= 1 && items[0].startsWith('removed by B') && items[0].includes('B line 13'),
          'diff: the region B removed, at its line: ' + items.join(' | '));
    check((await page.$eval('#verdict-line', (e) => e.textContent)).includes('DIFFERENT'), 'diff: the verdict DIFFERENT');
    await page.screenshot({ path: diffPage.replace(/\.html$/, '.png') });
    clean();
    await page.close();
  }
  // A holder collision in a subprogram file: listed, flown to, its line shown from that file; the
  // slider goes through the program in execution order, into the subprogram and back.
  {
    const { page, clean } = await open(holderPage);
    const report = JSON.parse(fs.readFileSync(path.join(out, 'holder.json')));
    const data = await pageData(page);
    check(report.collisions.length > 0 && report.collisions[0].line === 3 && report.collisions[0].file.endsWith('O1002.nc') &&
          report.collisions[0].part.startsWith('holder'),
          'holder: the report has the holder collision at O1002.nc:3: ' + JSON.stringify(report.collisions));
    check(data.files.length === 2 && data.files[1].name.endsWith('O1002.nc'), 'holder: both files in the page: ' +
          data.files.map((f) => f.name));
    const items = await page.$$eval('#findings li[data-finding]', (l) => l.map((e) => e.textContent));
    // Its two lines (the plunge and the retract) one entry, worst first, with both as members.
    const members = await page.$$eval('#findings li.member', (l) => l.map((e) => e.dataset.member));
    check(items[0].includes('holder of T1 rubs the material, O1002.nc lines 3–4, 2 moves, deepest ') && items[0].endsWith(' at line 3') &&
          JSON.stringify(members) === JSON.stringify(['collisions:0', 'collisions:1']),
          'holder: the collision is listed first, grouped: ' + items + ' ' + members);
    await toggle(page, 'show-path'); await toggle(page, 'show-rapids');
    const point = report.collisions[0].point;
    await chooseFinding(page, 'collisions:0');
    await settle(page);
    const seen = await page.evaluate((p) => window.tridexView.project(p), point);
    check(Math.abs(seen[0]) < 0.02 && Math.abs(seen[1]) < 0.02 && seen[2] > -1 && seen[2] < 1,
          'holder: the camera flew to the collision: ' + seen);
    const calm = await view(page, 'sample');
    check(calm.gouge === 0 && calm.background < 0.95 * calm.all, 'holder: no gouge-red pixels within the tolerance: ' + JSON.stringify(calm));
    const hits = await page.$$eval('#listing .hit', (l) => l.map((e) => e.textContent.trim()));
    const files = await page.$$eval('#listing .file', (l) => l.map((e) => e.textContent));
    check(hits.length === 2 && hits[0].startsWith('3') && hits[0].includes('G1 Z5 F300') && hits[1].includes('G0 Z40'),
          'holder: the subprogram\'s lines 3 and 4 marked, not the main file\'s: ' + hits);
    check(files.length === 1 && files[0].endsWith('O1002.nc'), 'holder: the listing names the subprogram file: ' + files);
    await toggle(page, 'show-path'); await toggle(page, 'show-rapids');
    await page.screenshot({ path: path.join(out, 'holder_collision.png') });
    // Stops: holder.nc:3, O1002.nc:2, 3, 4, holder.nc:5, 6, 7.
    const label = async () => page.$eval('#path-label', (e) => e.textContent);
    const stops = await page.$eval('#path-slider', (e) => Number(e.max) + 1);
    await setSlider(page, 2);
    const inSub = await label(), drawnInSub = await page.evaluate(() => window.tridexView.drawnSegments());
    await setSlider(page, 'max');
    const atEnd = await label(), drawnAtEnd = await page.evaluate(() => window.tridexView.drawnSegments());
    check(stops === 7 && inSub.startsWith('toolpath up to O1002.nc:3 ') && inSub.includes('G1 Z5 F300') &&
          atEnd.startsWith('toolpath up to holder.nc:7 '), 'holder: the slider in program order: ' + [stops, inSub, atEnd]);
    check(drawnInSub > 0 && drawnInSub < drawnAtEnd, 'holder: segments drawn in the subprogram ' + drawnInSub + ' of ' + drawnAtEnd);
    // The holder collision in view (ray cast), the tool drawn there.
    await checkInView(page, 'holder', report, data, ['collisions'], false);
    check((await page.evaluate(() => window.tridexView.toolShown())) === 1, 'holder: the tool is drawn at the collision');
    clean();
    await page.close();
  }
  // Faults on a face the first view does not show (issue 32): each gouge, excess and rapid cut in
  // view once chosen; playback shows the stock at step 0 and the part at the last step.
  {
    const { page, clean } = await open(facePage);
    await page.setViewport({ width: 1280, height: 720 });
    await settle(page);
    const report = JSON.parse(fs.readFileSync(path.join(out, 'face.json'))), data = await pageData(page);
    // The list is reachable without scrolling at 1280 × 720: its first entry within the window.
    const first = await page.$eval('#findings li', (e) => e.getBoundingClientRect().bottom);
    check(first < 720, 'face: the first finding is on screen at 1280 × 720: ' + first);
    // From the first view (which turns to the side the program cuts): step 0 against the last.
    const played = await playbackDiff(page);
    await page.screenshot({ path: path.join(out, 'face_first_view_last_step.png') });
    console.log('face: step 0 and the last step differ in ' + (100 * played.fraction).toFixed(1) + ' % of the view\'s pixels');
    check(played.fraction >= 0.02, 'face: step 0 and the last step differ in ' + (100 * played.fraction).toFixed(1) + ' % of the pixels');
    check(played.stockFirst > played.stockHalf && played.stockHalf > 0 && played.stockLast === 0,
          'face: less stock left as the program runs: ' + JSON.stringify(played));
    const steps = await view(page, 'steps');
    check(steps === data.toolpath.stop_count && steps > 10, 'face: steps() is the program\'s stop count: ' + steps);
    await checkInView(page, 'face', report, data, ['gouges', 'excess', 'rapid_cuts'], true);
    await view(page, 'step', 0);
    await page.screenshot({ path: path.join(out, 'face_step0.png') });
    await view(page, 'step', Math.floor(steps / 2));
    check((await view(page, 'toolShown')) === 1, 'face: the tool drawn at the slider');
    await page.screenshot({ path: path.join(out, 'face_step_half.png') });
    await view(page, 'layer', 'tool', false);
    check((await view(page, 'toolShown')) === 0, 'face: the tool layer hides it');
    // Play: the slider moves on by itself.
    await view(page, 'step', 0);
    await page.select('#speed', '2');
    await toggle(page, 'play');
    await page.waitForFunction(() => Number(document.getElementById('path-slider').value) > 0, { timeout: 10000 });
    // Pause, unless playing already reached the end and stopped (a slow frame under load can jump
    // there, and a click then would start again from step 0).
    await page.evaluate(() => { const play = document.getElementById('play'); if (play.textContent === 'pause') play.click(); });
    check(Number(await page.$eval('#path-slider', (e) => e.value)) > 0, 'face: play moves the slider');
    // The print style: one A4 page, with a picture of each of the worst findings.
    await page.evaluate(() => window.dispatchEvent(new Event('beforeprint')));
    check((await page.$$('#print-shots img')).length === 3, 'face: pictures of the three worst findings for print');
    const pdf = Buffer.from(await page.pdf({ format: 'A4', printBackground: true }));
    fs.writeFileSync(path.join(out, 'face_print.pdf'), pdf);
    const pages = (pdf.toString('latin1').match(/\/Type\s*\/Page\s/g) || []).length;
    check(pages === 1, 'face: the print style gives one page: ' + pages);
    await page.emulateMediaType('print');
    await page.screenshot({ path: path.join(out, 'face_print.png'), fullPage: true });
    await page.emulateMediaType(null);
    clean();
    await page.close();
  }
  // The large program: the slider's label shows the line's text, inflated from its chunk.
  {
    const { page, clean } = await open(largePage);
    const data = await pageData(page);
    check(data.files[0].chunks && data.files[0].chunks.length === Math.ceil(largeLines.length / data.files[0].chunk_lines),
          'large: the text in compressed chunks: ' + (data.files[0].chunks || []).length + ', ' + data.files[0].note);
    const stops = await page.$eval('#path-slider', (e) => Number(e.max) + 1);
    for (const stop of [Math.floor(stops / 3), stops - 2, 1]) {
      await setSlider(page, stop);
      await page.waitForFunction(() => !document.getElementById('path-label').textContent.endsWith('…'), { timeout: 30000, polling: 100 });
      const label = await page.$eval('#path-label', (e) => e.textContent);
      const line = Number(/up to line (\d+) /.exec(label)[1]);
      check(label.endsWith(': ' + largeLines[line - 1]), 'large: the slider at line ' + line + ' shows its text: ' + label);
    }
    clean();
    await page.close();
  }
  // The machine check (issue 33): the fixture drawn from the start; choosing the machine finding
  // draws its pair (the clamp and the spindle nose) at the finding's pose in teal; the machine
  // layer hides them.
  {
    const { page, clean } = await open(machinePage);
    const report = JSON.parse(fs.readFileSync(path.join(out, 'machine_report.json'))), data = await pageData(page);
    check(report.machine.collisions.length === 1 && report.machine.collisions[0].line === 5 &&
          report.machine.collisions[0].b === 'spindle nose', 'machine: the nose onto the clamp at line 5: ' + JSON.stringify(report.machine.collisions));
    check(await page.$eval('#machine-toggle', (e) => !e.hidden), 'machine: the machine layer is offered');
    await toggle(page, 'show-path'); await toggle(page, 'show-rapids');
    const first = await view(page, 'machineShown');
    check(JSON.stringify(first) === JSON.stringify({ fixtures: ['clamp.stl'], pair: [] }), 'machine: the fixture drawn at first: ' + JSON.stringify(first));
    const before = await view(page, 'sample');
    check(before.machine < 0.001 * before.all, 'machine: no teal before a finding is chosen: ' + JSON.stringify(before));
    await chooseFinding(page, 'machine.collisions:0');
    await settle(page);
    const chosen = await view(page, 'machineShown');
    check(JSON.stringify(chosen.pair) === JSON.stringify(['clamp.stl', 'spindle nose']), 'machine: the pair drawn once chosen: ' + JSON.stringify(chosen));
    const drawn = await view(page, 'sample');
    check(drawn.machine > 0.01 * drawn.all, 'machine: teal pixels of the pair: ' + JSON.stringify(drawn));
    // Where the nose stands: its gauge point 60 mm above the tip at the contact (the clamp's top, Z45).
    const nose = data.machine.collisions[0][1].matrix;
    check(Math.abs(nose[3] - 85) < 1e-6 && Math.abs(nose[11] - 45.5) < 0.05, 'machine: the nose placed at the finding\'s pose: ' + nose);
    await page.screenshot({ path: path.join(out, 'machine_collision.png') });
    // Printing draws each finding in turn, then puts the chosen one's pair back.
    await page.evaluate(() => window.dispatchEvent(new Event('beforeprint')));
    check(JSON.stringify((await view(page, 'machineShown')).pair) === JSON.stringify(chosen.pair), 'machine: the pair again after printing');
    await view(page, 'layer', 'machine', false);
    const hidden = await view(page, 'sample');
    check(hidden.machine < 0.001 * hidden.all && (await view(page, 'machineShown')).pair.length === 0,
          'machine: the machine layer hides the pair: ' + JSON.stringify(hidden));
    clean();
    await page.close();
  }
  {
    const { page, clean } = await open(unplacedPage);
    const said = await page.$$eval('#not-checked .message', (l) => l.map((e) => e.textContent));
    check(said.length === 1 && said[0].startsWith('Not checked: the spindle\'s parts not tested with T1'),
          'unplaced: "not checked" by the verdict: ' + said);
    const verdict = await page.$eval('#verdict-line', (e) => e.getBoundingClientRect().bottom);
    const message = await page.$eval('#not-checked .message', (e) => e.getBoundingClientRect().top);
    check(message >= verdict && message < verdict + 40, 'unplaced: right under the verdict: ' + [verdict, message]);
    const warnings = await page.$$eval('#summary tr', (l) => l.filter((r) => r.cells[0].textContent === 'warning').map((r) => r.cells[1].textContent));
    check(warnings.some((w) => w.startsWith('the spindle\'s parts not tested with T1')), 'unplaced: among the warnings: ' + warnings);
    await page.screenshot({ path: path.join(out, 'unplaced.png') });
    clean();
    await page.close();
  }
  // The legend overlaps no control of the toolbar (nor the slider's box) at 1280 × 800, with one
  // direction and with five.
  for (const file of [checkPage, manyPage]) {
    const { page, clean } = await open(file);
    const rects = await page.evaluate(() => {
      const r = (e) => { const b = e.getBoundingClientRect(); return { name: e.id || e.textContent.trim() || e.tagName, l: b.left, t: b.top, r: b.right, b: b.bottom }; };
      const controls = [...document.querySelectorAll('#toolbar button, #toolbar label, #toolbar select, #toolbar input')]
        .filter((e) => e.offsetParent !== null).map(r);
      return { legend: r(document.getElementById('legend')), controls, bottom: r(document.getElementById('bottom')),
               rows: new Set(controls.map((c) => Math.round(c.t))).size };
    });
    const overlaps = (a, b) => a.l < b.r && b.l < a.r && a.t < b.b && b.t < a.b;
    const hit = rects.controls.filter((c) => overlaps(c, rects.legend)).map((c) => c.name);
    check(hit.length === 0 && !overlaps(rects.legend, rects.bottom), path.basename(file) + ': the legend covers ' + hit + ' ' + JSON.stringify(rects.legend));
    if (file === manyPage) check(rects.rows >= 2, 'many: the toolbar wraps at 1280 × 800: ' + rects.rows + ' rows');
    await page.screenshot({ path: file.replace(/\.html$/, '_legend.png') });
    clean();
    await page.close();
  }
  // Nothing to show: the page says so and still works.
  for (const [file, message] of [[emptyPage, 'No material is left'], [noMovesPage, 'The program has no moves']]) {
    const { page, clean } = await open(file);
    const messages = await page.$$eval('.message', (l) => l.map((e) => e.textContent));
    check(messages.some((m) => m.startsWith(message)), path.basename(file) + ': says "' + message + '": ' + messages);
    await page.screenshot({ path: file.replace(/\.html$/, '.png') });
    clean();
    await page.close();
  }
} catch (e) {
  ++failed;
  console.log('FAILED: ' + (e.stack || e));
} finally {
  await browser.close();
  fs.rmSync(profile, { recursive: true, force: true });
}
console.log('screenshots in ' + out);
console.log(`html report: ${passed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);
