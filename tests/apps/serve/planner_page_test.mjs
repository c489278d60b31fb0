// The planner page in a real browser (Debian's chromium, headless, driven by playwright-core; never a
// downloaded browser), as a user clicks. Run by planner_page_browser_test.cc, which starts the server and
// makes the reference plan with `pectus plan`:
//   node planner_page_test.mjs URL PATIENT REFERENCE_REPORT.json REFERENCE.png OUT_DIR [--update-reference]
// Checks, each to a stated tolerance: no console error; the canvas is not blank; the page's deformed skin
// equals the C++ deform call's within 0.01 mm; its figures equal `pectus plan`'s within 0.01 mm; the bar
// moved by keyboard, slider and dragging changes the skin and the figures; scenarios A/B; the search and
// a click on its map; a plan's round trip; a screenshot against the stored one (<= 0.5 % of pixels).
// Prints the timings (first frame, update, frames per second while dragging) as JSON, then
// "N passed, M failed".
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { createRequire } from 'node:module';

const require = createRequire(path.resolve(process.env.PECTUS_PAGE_DIR ?? '.', 'package.json'));
const { chromium } = require('playwright-core');

const [url, patient, referencePath, screenshotPath, outDir, ...flags] = process.argv.slice(2);
const update = flags.includes('--update-reference');
const results = [];
function check(name, ok, detail = '') {
  results.push({ name, ok });
  console.log(`${ok ? 'PASS' : 'FAIL'} ${name}${detail ? ': ' + detail : ''}`);
}

const userDataDir = fs.mkdtempSync(path.join(os.tmpdir(), 'pectus-chromium-'));
// A fresh --user-data-dir (playwright passes it as the persistent context's folder).
const context = await chromium.launchPersistentContext(userDataDir, {
  executablePath: '/usr/bin/chromium',
  headless: true,
  viewport: { width: 1280, height: 800 },
  acceptDownloads: true,
  // WebGL in SwiftShader (no GPU here); the page's layers composited by Chromium's software compositor
  // (planner_page_benchmark.mjs says why).
  args: ['--headless', '--no-sandbox', '--enable-unsafe-swiftshader', '--use-angle=swiftshader', '--disable-background-networking',
    '--disable-component-update', '--disable-sync', '--no-first-run', '--disable-gpu-compositing',
    ...(process.env.PECTUS_DISABLE_GPU ? ['--disable-gpu'] : [])],
});
let exitCode = 1;
try {
  const page = context.pages()[0] ?? (await context.newPage());
  const errors = [];
  page.on('console', (m) => m.type() === 'error' && errors.push(m.text()));
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('response', async (r) => r.status() >= 400 && errors.push(`${r.status()} ${r.url().replace(/token=[0-9a-f]+/, 'token=…')}: ${await r.text().catch(() => '')}`));
  const reference = JSON.parse(fs.readFileSync(referencePath, 'utf8'));
  const refA = reference.scenarios[0].bar;

  // 1. The page loads and draws the patient with scenario A of the reference plan.
  const t0 = Date.now();
  await page.goto(`${url}&patient=${encodeURIComponent(patient)}`);
  await page.waitForFunction(() => window.pectus?.state.plan && window.pectus.state.live, null, { timeout: 120000 });
  await page.waitForFunction(() => window.pectus.firstFrameMs() !== null, null, { timeout: 60000 });
  const firstFrameMs = await page.evaluate(() => window.pectus.firstFrameMs());
  await page.evaluate((a) => window.pectus.setBar({ position: a.position, force: a.force_n }), refA);
  const planFor = (bar) => page.waitForFunction((b) => {
    const s = window.pectus.state;
    return s.plan && s.planFor && Math.abs(s.planFor.position - b.position) < 1e-12 && Math.abs(s.planFor.force - b.force) < 1e-9;
  }, bar, { timeout: 60000 });
  await planFor({ position: refA.position, force: refA.force_n });
  await page.waitForTimeout(300);
  check('no console error', errors.length === 0, errors.join(' | '));

  // 2. The canvas is not blank: pixel statistics of a screenshot of it.
  const canvasPng = await page.locator('canvas').first().screenshot();
  const stats = await page.evaluate(async (b64) => {
    const img = await createImageBitmap(await (await fetch(`data:image/png;base64,${b64}`)).blob());
    const c = new OffscreenCanvas(img.width, img.height);
    const g = c.getContext('2d');
    g.drawImage(img, 0, 0);
    const d = g.getImageData(0, 0, img.width, img.height).data;
    let drawn = 0;
    const colours = new Set();
    for (let i = 0; i < d.length; i += 4) {
      if (Math.abs(d[i] - 244) + Math.abs(d[i + 1] - 244) + Math.abs(d[i + 2] - 244) > 12) ++drawn;
      colours.add((d[i] >> 3) * 1024 + (d[i + 1] >> 3) * 32 + (d[i + 2] >> 3));
    }
    return { drawnFraction: drawn / (d.length / 4), colours: colours.size };
  }, canvasPng.toString('base64'));
  check('canvas is not blank', stats.drawnFraction > 0.05 && stats.colours > 50, JSON.stringify(stats));

  // 3. The page's deformation from the basis equals the C++ deform call's, 0.01 mm.
  const deformation = await page.evaluate(async (id) => {
    const token = new URLSearchParams(location.search).get('token');
    const L = window.pectus.state.info.sternal_length_mm;
    let worst = 0, worstLift = 0;
    for (const [fraction, force] of [[0.8123, 200], [0.6007, 733], [0.9, 1500], [0.55, 90]]) {
      const mm = fraction * L;
      const r = await fetch('/api/deform', { method: 'POST', headers: { 'X-Pectus-Token': token, 'Content-Type': 'application/json' },
        body: JSON.stringify({ patient: id, bar: { position: mm, position_in_mm: true, force_n: force } }) });
      const cpp = await r.json();
      const js = window.pectus.deformSkin(mm, force);
      for (let i = 0; i < js.length; ++i) worst = Math.max(worst, Math.abs(js[i] - cpp.skin[i]));
      const lift = window.pectus.liftAt(mm, force);
      worstLift = Math.max(worstLift, Math.abs(lift - cpp.sternum_lift_mm));
    }
    return { worst, worstLift };
  }, patient);
  check('deformed skin equals the C++ deform call within 0.01 mm', deformation.worst <= 0.01 && deformation.worstLift <= 0.01, JSON.stringify(deformation));

  // 4. The figures equal `pectus plan`'s for the same plan, 0.01 mm: in the state and as shown.
  const shown = await page.evaluate(() => {
    const s = window.pectus.state;
    const text = (id) => Number(document.getElementById(id)?.textContent);
    return { plan: s.plan, rms: [0, 1].map((i) => text(`exact-rms-${i}`)), max: [0, 1].map((i) => text(`exact-max-${i}`)),
      central: [0, 1].map((i) => text(`exact-central-${i}`)), lift: [0, 1].map((i) => text(`exact-lift-${i}`)) };
  });
  let worstFigure = 0;
  for (let i = 0; i < 2; ++i) {
    const want = reference.scenarios[i], got = shown.plan.scenarios[i];
    for (const [w, g, t] of [[want.score.rms_mm, got.score.rms_mm, shown.rms[i]], [want.score.max_abs_mm, got.score.max_abs_mm, shown.max[i]],
      [want.score.central.rms_mm, got.score.central.rms_mm, shown.central[i]], [want.sternum_lift_mm, got.sternum_lift_mm, shown.lift[i]]]) {
      worstFigure = Math.max(worstFigure, Math.abs(w - g), Math.abs(w - t) - 0.005); // shown to 0.01: rounding is 0.005
    }
    if (want.bar.position_in_mm !== got.bar.position_in_mm || Math.abs(want.bar.position - got.bar.position) > 1e-9) worstFigure = Infinity;
  }
  check('figures of scenarios A and B equal pectus plan within 0.01 mm', worstFigure <= 0.01, `worst ${worstFigure}`);

  // 5. The screenshot against the stored one (<= 0.5 % of the pixels differ by more than 24 levels).
  fs.mkdirSync(outDir, { recursive: true });
  fs.writeFileSync(path.join(outDir, 'planner_page.png'), canvasPng);
  if (update || !fs.existsSync(screenshotPath)) {
    fs.writeFileSync(screenshotPath, canvasPng);
    check('stored screenshot written (no comparison)', update, screenshotPath);
  } else {
    const differing = await page.evaluate(async ([a, b]) => {
      const load = async (b64) => createImageBitmap(await (await fetch(`data:image/png;base64,${b64}`)).blob());
      const [x, y] = [await load(a), await load(b)];
      if (x.width !== y.width || x.height !== y.height) return 1;
      const pixels = (img) => {
        const c = new OffscreenCanvas(img.width, img.height);
        const g = c.getContext('2d');
        g.drawImage(img, 0, 0);
        return g.getImageData(0, 0, img.width, img.height).data;
      };
      const [p, q] = [pixels(x), pixels(y)];
      let n = 0;
      for (let i = 0; i < p.length; i += 4) if (Math.max(Math.abs(p[i] - q[i]), Math.abs(p[i + 1] - q[i + 1]), Math.abs(p[i + 2] - q[i + 2])) > 24) ++n;
      return n / (p.length / 4);
    }, [canvasPng.toString('base64'), fs.readFileSync(screenshotPath).toString('base64')]);
    check('screenshot equals the stored one (<= 0.5 % of pixels differ)', differing <= 0.005, `${(100 * differing).toFixed(3)} %`);
  }

  // 6. Keyboard, slider and dragging move the bar; the skin and the figures follow.
  const snapshot = () => page.evaluate(() => {
    const s = window.pectus.state;
    const skin = window.pectus.skinPositions();
    let sum = 0;
    for (let i = 0; i < skin.length; ++i) sum += skin[i] * ((i % 7) + 1);
    return { bar: { ...s.bar }, lift: s.live.liftMm, skin: sum, rms: s.plan?.scenarios[0].score.rms_mm };
  });
  const before = await snapshot();
  await page.locator('canvas').first().focus();
  for (let i = 0; i < 5; ++i) await page.keyboard.press('ArrowUp');
  for (let i = 0; i < 3; ++i) await page.keyboard.press('ArrowRight');
  await page.waitForFunction(() => window.pectus.state.live.force === window.pectus.state.bar.force, null, { timeout: 30000 });
  const keyed = await snapshot();
  const L = await page.evaluate(() => window.pectus.state.info.sternal_length_mm);
  check('arrow keys move the bar 5 mm up and 15 N more', Math.abs((before.bar.position - keyed.bar.position) * L - 5) < 1e-6 && Math.abs(keyed.bar.force - before.bar.force - 15) < 1e-9,
    JSON.stringify([before.bar, keyed.bar]));
  check('the deformed skin and the live lift change with the bar', keyed.skin !== before.skin && Math.abs(keyed.lift - before.lift) > 1e-3, JSON.stringify([before.lift, keyed.lift]));
  await planFor(keyed.bar);
  const keyedPlan = await snapshot();
  check('the exact figures follow the bar', Math.abs(keyedPlan.rms - before.rms) > 1e-6, JSON.stringify([before.rms, keyedPlan.rms]));
  const drawn = () => page.waitForFunction(() => {
    const s = window.pectus.state;
    return s.live.position === s.bar.position && s.live.force === s.bar.force;
  }, null, { timeout: 30000 });
  await page.locator('#force').fill('400');
  await drawn();
  const slid = await snapshot();
  check('the force slider sets the force and the lift doubles with it', slid.bar.force === 400 && Math.abs(slid.lift / keyedPlan.lift - 400 / keyedPlan.bar.force) < 1e-6, JSON.stringify(slid));
  // Dragging (Shift-drag anywhere) for about a second: frames per second while the bar moves.
  const box = await page.locator('canvas').first().boundingBox();
  const rendersBefore = await page.evaluate(() => window.pectus.renders());
  await page.keyboard.down('Shift');
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.down();
  const dragStart = Date.now();
  for (let i = 0; i < 30; ++i) await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2 - i, { steps: 1 });
  await page.mouse.up();
  await page.keyboard.up('Shift');
  const dragSeconds = (Date.now() - dragStart) / 1000;
  const frames = (await page.evaluate(() => window.pectus.renders())) - rendersBefore;
  const dragged = await snapshot();
  check('dragging moves the bar towards the notch', dragged.bar.position < slid.bar.position - 1e-4, JSON.stringify([slid.bar, dragged.bar]));

  // 7. Scenarios A and B side by side.
  await planFor(dragged.bar);
  const ab = await page.evaluate(() => {
    const s = window.pectus.state, L = s.info.sternal_length_mm;
    const [a, b] = s.plan.scenarios;
    return { names: [a.name, b.name], gap: a.bar.position * L - b.bar.position, shownB: document.getElementById('exact-rms-1')?.textContent };
  });
  check('scenarios A and B side by side, B 20 mm nearer the notch', ab.names.join() === 'A,B' && Math.abs(ab.gap - 20) < 1e-6 && Number(ab.shownB) > 0, JSON.stringify(ab));

  // 8. The search and its map: a click on a cell loads that placement.
  await page.click('#search');
  await page.waitForFunction(() => window.pectus.state.search, null, { timeout: 120000 });
  const grid = await page.evaluate(() => ({ positions: window.pectus.state.search.positions, forces: window.pectus.state.search.forces_n }));
  const map = await page.locator('#search-map canvas').boundingBox();
  const [ci, cj] = [2, 5];
  await page.mouse.click(map.x + (cj + 0.5) * (map.width / grid.forces.length), map.y + (ci + 0.5) * (map.height / grid.positions.length));
  const clicked = await snapshot();
  check('a click on the search map loads that cell', Math.abs(clicked.bar.position - grid.positions[ci]) < 1e-12 && Math.abs(clicked.bar.force - grid.forces[cj]) < 1e-9,
    JSON.stringify([clicked.bar, grid.positions[ci], grid.forces[cj]]));

  // 9. A saved plan's round trip: exported, another bar set, the plan loaded back.
  await planFor(clicked.bar);
  const saved = await page.evaluate(() => window.pectus.planJson());
  const savedPlan = JSON.parse(saved);
  const keys = Object.keys(savedPlan.scenarios[0]).sort().join();
  await page.evaluate(() => window.pectus.setBar({ position: 0.7, force: 123 }));
  await page.evaluate((text) => window.pectus.loadPlan(text), saved);
  const loaded = await snapshot();
  check('a plan saved and loaded gives its bar back, in the schema of pectus plan --report',
    Math.abs(loaded.bar.position - clicked.bar.position) < 1e-12 && Math.abs(loaded.bar.force - clicked.bar.force) < 1e-9 &&
      keys === Object.keys(reference.scenarios[0]).sort().join(), JSON.stringify(loaded.bar));

  // 10. The trainer: a scripted session end to end with the pointer as the device: started from the panel,
  // the pointer dragged along the planned tunnel (right port, under the sternum, left port), the tip
  // followed by the server's haptic loop, the scope's view inset drawn, the live score shown, then finished:
  // the report, its scores as the record replays to, and the record.
  await page.selectOption('#trainer-introducer', 'medium');
  await page.click('#trainer-start');
  await page.waitForFunction(() => window.pectus.state.trainer.tick && window.pectus.state.trainer.scope, null, { timeout: 60000 });
  const route = await page.evaluate(() => {
    const t = window.pectus.state.trainer.info, tr = window.pectus.trainer;
    const pts = [t.start_mm];
    for (let i = 0; i < t.tunnel.points.length; i += 3) pts.push(t.tunnel.points[i]);
    const n = t.tunnel.points.length, last = t.tunnel.points[n - 1], before = t.tunnel.points[Math.max(0, n - 6)];
    const d = last.map((v, k) => v - before[k]), len = Math.hypot(...d);
    for (const s of [10, 20, 30]) pts.push(last.map((v, k) => v + (s * d[k]) / len));
    // Each point as the pointer reaches it, on the working plane (the tunnel is planar within a few mm).
    return pts.map((p) => tr.screenOf(p));
  });
  await page.mouse.move(route[0].x, route[0].y);
  await page.mouse.down();
  const sessionStart = Date.now();
  // One pointer event a point: the device glides in a straight line to each target anyway, and each event
  // waits for a frame of the page (SwiftShader), 0.3 s under the sanitizers.
  for (const [i, p] of route.slice(1).entries()) {
    await page.mouse.move(p.x, p.y);
    await page.waitForTimeout(40);
    // The picture of docs/trainer.md, half way under the sternum: PECTUS_TRAINER_PICTURE=FILE.png.
    if (process.env.PECTUS_TRAINER_PICTURE && i === Math.floor(route.length / 2)) {
      await page.waitForTimeout(300);
      await page.screenshot({ path: process.env.PECTUS_TRAINER_PICTURE });
    }
  }
  await page.mouse.up();
  // The server's device has reached the last target (its glide and the requests keep up at their own pace:
  // slower under the sanitizers), then 200 more servo ticks for the proxy to follow, and an answer after.
  const reachedTick = (await page.waitForFunction(() => {
    const s = window.pectus.state.trainer, t = s.target, d = s.tick?.device_mm;
    return d && Math.hypot(d[0] - t[0], d[1] - t[1], d[2] - t[2]) < 0.5 && s.tick.tick;
  }, null, { timeout: 60000 })).jsonValue();
  await page.waitForFunction((n) => window.pectus.state.trainer.tick.tick > n + 200, await reachedTick, { timeout: 60000 });
  const live = await page.evaluate(() => {
    const s = window.pectus.state.trainer;
    const exit = s.info.tunnel.exit_port_mm;
    return {
      proxyBeyondExit: s.tick.proxy_mm[0] > exit[0], proxy: s.tick.proxy_mm, exit,
      score: document.getElementById('trainer-score')?.textContent, distance: document.getElementById('trainer-distance')?.textContent,
      inset: window.pectus.trainer.inset, ticks: s.tick.tick,
    };
  });
  check('the pointer drags the introducer through the tunnel and out beyond the left port', live.proxyBeyondExit, JSON.stringify(live));
  check('the live score and the distance to the pericardium are shown', Number(live.score) > 0 && /mm/.test(live.distance ?? ''), JSON.stringify(live));
  check('the servo loop ran at about 1 kHz during the drag', live.ticks > 0.5 * (Date.now() - sessionStart), JSON.stringify({ ticks: live.ticks, ms: Date.now() - sessionStart }));
  // The scope's view: its corner of the canvas is drawn (not the clear colour alone) and shows the scene.
  const shot = await page.locator('canvas').first().screenshot();
  const inset = await page.evaluate(async ([b64, box]) => {
    const img = await createImageBitmap(await (await fetch(`data:image/png;base64,${b64}`)).blob());
    const c = new OffscreenCanvas(img.width, img.height);
    const g = c.getContext('2d');
    g.drawImage(img, 0, 0);
    const d = g.getImageData(box.x, img.height - box.y - box.height, box.width, box.height).data;
    let dark = 0, drawn = 0;
    for (let i = 0; i < d.length; i += 4) {
      if (Math.abs(d[i] - 0x1a) + Math.abs(d[i + 1] - 0x0f) + Math.abs(d[i + 2] - 0x0a) < 6) ++dark;
      else ++drawn;
    }
    return { background: dark / (d.length / 4), drawn: drawn / (d.length / 4) };
  }, [shot.toString('base64'), live.inset]);
  check('the thoracoscope view is inset and shows the scene', inset.background > 0.01 && inset.drawn > 0.2, JSON.stringify(inset));
  await page.click('#trainer-finish');
  await page.waitForFunction(() => window.pectus.state.trainer.report, null, { timeout: 60000 });
  const report = await page.evaluate(() => ({
    r: window.pectus.state.trainer.report,
    shown: document.getElementById('trainer-report-score')?.textContent,
    replay: document.getElementById('trainer-report-replay')?.textContent,
  }));
  const sc = report.r.score;
  check('the report: entry and exit through the planned spaces, no pericardial contact',
    sc.entry_as_planned && sc.exit_as_planned && sc.pericardial_contacts === 0 && sc.min_pericardium_distance_mm > 1, JSON.stringify(sc));
  check('the report is shown and its record replays to the same scores', Number(report.shown) === Number(sc.score.toFixed(1)) && report.replay === 'yes' && report.r.replay_gives_the_same_scores,
    JSON.stringify({ shown: report.shown, replay: report.replay }));
  const bar = report.r.bar;
  check("the report gives the bar's outcome through this tunnel against the average chest",
    bar?.score?.rms_mm > 0 && bar.score.rms_mm < bar.before.rms_mm && bar.force_n > 0 && bar.position > 0.3 && bar.position <= 1, JSON.stringify(bar && { ...bar, score: bar.score?.rms_mm, before: bar.before?.rms_mm }));
  const record = await page.evaluate(() => window.pectus.trainer.recordText());
  const tickLines = record.split('\n').filter((l) => l.startsWith('tick ')).length;
  check('the record holds every tick of the session', tickLines === sc.ticks && /patient\s+57/.test(record), JSON.stringify({ tickLines, ticks: sc.ticks, head: record.slice(0, 80) }));
  // The bar pulled through the tunnel and flipped: the chest deforms as it turns, to the lift the report's
  // force gives (the sternum raised by its depression), from the page's basis.
  await page.click('#trainer-pass-bar');
  await page.waitForFunction(() => window.pectus.state.trainer.bar?.phase === 'flipped' && window.pectus.state.live?.force === window.pectus.state.bar.force, null, { timeout: 30000 });
  const flipped = await page.evaluate(() => ({ lift: window.pectus.state.live.liftMm, depression: window.pectus.state.info.depression_mm, status: document.getElementById('trainer-bar-status')?.textContent }));
  if (process.env.PECTUS_TRAINER_BAR_PICTURE) await page.screenshot({ path: process.env.PECTUS_TRAINER_BAR_PICTURE });
  check('the bar pulled through and flipped lifts the sternum by its depression', Math.abs(flipped.lift - flipped.depression) < 0.05 && /flipped/.test(flipped.status), JSON.stringify(flipped));
  await page.click('#trainer-place-bar');
  const placed = await page.evaluate(() => ({ bar: window.pectus.state.bar, visible: window.pectus.scene.bar.visible, skin: window.pectus.state.view.skin, trainer: window.pectus.state.trainer.session }));
  check('back to the planner with the bar placed through the tunnel: the bar and the skin again',
    placed.visible && placed.skin && placed.trainer === null && Math.abs(placed.bar.position - bar.position) < 1e-12 && Math.abs(placed.bar.force - bar.force_n) < 1e-9, JSON.stringify(placed));
  console.log(JSON.stringify({ trainer_score: sc.score, trainer_ticks: sc.ticks, trainer_loop_p99_ms: report.r.loop.period_p99_ms }));

  // Timings: the deformation update per frame (whole surface: bone, skin, landmarks), mean of 200.
  const updateMs = await page.evaluate(() => window.pectus.timeUpdate(200));
  console.log(JSON.stringify({ first_frame_ms: firstFrameMs, whole_test_ms: Date.now() - t0, update_ms: updateMs, drag_fps: frames / dragSeconds }));
  check('no console error after all of it', errors.length === 0, errors.join(' | '));
  exitCode = results.every((r) => r.ok) ? 0 : 1;
} catch (e) {
  console.log(`FAIL ${e.stack ?? e}`);
  results.push({ ok: false });
} finally {
  await context.close();
  fs.rmSync(userDataDir, { recursive: true, force: true });
}
const failed = results.filter((r) => !r.ok).length;
console.log(`${results.length - failed} passed, ${failed} failed`);
process.exit(failed ? 1 : exitCode);
