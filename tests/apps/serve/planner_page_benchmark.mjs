// Timings of the planner page in headless Chromium (Debian's, with SwiftShader: software WebGL), against a
// running `pectus serve` whose patient is made (it says "ready"):
//   node tests/apps/serve/planner_page_benchmark.mjs URL [--patient ID] [--loads 5] [--drag-seconds 3]
//       [--width 1280 --height 800] [--gpu-compositing]
// (run from anywhere; playwright-core is taken from apps/planner_page/node_modules). Prints JSON:
//   first_frame_ms  per page load, from navigation's start to the patient drawn (the page's own clock),
//                   with the steps: script running, average chest drawn, patient downloaded, scene built;
//   frame_ms        a frame whose bar moved, at rest resolution and at the moving one: deformation from
//                   the basis, meshes moved (normals), drawing to the end of the GPU's work;
//   drag_driver     a pointer drag of the bar (Shift-drag) by the driver's mouse, as fast as the browser
//                   takes the moves (each a round trip), for --drag-seconds: frames drawn per second;
//   drag_125hz      the same drag with the pointer moving at 125 Hz (faster than the frames, as a mouse
//                   does) through the page's pointer handlers: the frames per second the page reaches.
import os from 'node:os';
import fs from 'node:fs';
import path from 'node:path';
import { createRequire } from 'node:module';
import { fileURLToPath } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const require = createRequire(path.resolve(here, '../../../apps/planner_page/package.json'));
const { chromium } = require('playwright-core');

const argv = process.argv.slice(2);
const url = argv[0];
const flag = (name, fallback) => {
  const i = argv.indexOf(`--${name}`);
  return i >= 0 ? argv[i + 1] : fallback;
};
if (!url || !url.includes('token=')) {
  console.error('usage: planner_page_benchmark.mjs URL (as `pectus serve` printed it) [--patient ID] [--loads N] [--drag-seconds S]');
  process.exit(2);
}
const patient = flag('patient', null);
const loads = Number(flag('loads', 5));
const dragSeconds = Number(flag('drag-seconds', 3));
const viewport = { width: Number(flag('width', 1280)), height: Number(flag('height', 800)) };
const pageUrl = patient ? `${url}&patient=${encodeURIComponent(patient)}` : url;
// Without a GPU, WebGL runs in SwiftShader either way; the page's layers are composited by Chromium's own
// software compositor (the default here, as the browser test runs) or, with --gpu-compositing, through
// SwiftShader as well (Chromium's default when it is told nothing: a fixed 25 ms a frame on this machine).
const gpuCompositing = argv.includes('--gpu-compositing');

const userDataDir = fs.mkdtempSync(path.join(os.tmpdir(), 'pectus-chromium-bench-'));
const context = await chromium.launchPersistentContext(userDataDir, {
  executablePath: '/usr/bin/chromium',
  headless: true,
  viewport,
  args: ['--headless', '--no-sandbox', '--enable-unsafe-swiftshader', '--use-angle=swiftshader', '--disable-background-networking',
    '--disable-component-update', '--disable-sync', '--no-first-run', ...(gpuCompositing ? [] : ['--disable-gpu-compositing'])],
});
const median = (v) => [...v].sort((a, b) => a - b)[Math.floor(v.length / 2)];
try {
  const page = context.pages()[0] ?? (await context.newPage());
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  // First frames: fresh loads of the page (the browser's cache is off: the server says no-store).
  const firsts = [];
  for (let i = 0; i < loads; ++i) {
    await page.goto(pageUrl);
    await page.waitForFunction(() => window.pectus?.firstFrameMs() !== null && window.pectus?.firstFrameMs() !== undefined, null, { timeout: 120000 });
    firsts.push(await page.evaluate(() => window.pectus.startTimings()));
  }
  await page.waitForFunction(() => window.pectus.state.plan, null, { timeout: 60000 });
  const renderer = await page.evaluate(() => {
    const gl = document.querySelector('canvas').getContext('webgl2');
    const info = gl.getExtension('WEBGL_debug_renderer_info');
    return info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER);
  });
  // Frames whose bar moved, at rest and at the moving resolution.
  const atRest = await page.evaluate(() => window.pectus.timeFrames(30));
  await page.evaluate(() => window.pectus.setMoving(true));
  const moving = await page.evaluate(() => window.pectus.timeFrames(30));
  await page.evaluate(() => window.pectus.setMoving(false));
  // A real drag: Shift-drag from the middle of the view, moving a pixel at a time up and down.
  const box = await page.locator('canvas').first().boundingBox();
  const x = box.x + box.width / 2, y = box.y + box.height / 2;
  const before = await page.evaluate(() => ({ renders: window.pectus.renders(), position: window.pectus.state.bar.position }));
  await page.keyboard.down('Shift');
  await page.mouse.move(x, y);
  await page.mouse.down();
  const start = Date.now();
  let moves = 0;
  while (Date.now() - start < dragSeconds * 1000) {
    await page.mouse.move(x, y - 40 + Math.abs((moves % 160) - 80), { steps: 1 });
    ++moves;
  }
  const seconds = (Date.now() - start) / 1000;
  const after = await page.evaluate(() => ({ renders: window.pectus.renders(), position: window.pectus.state.bar.position }));
  await page.mouse.up();
  await page.keyboard.up('Shift');
  // The same drag with the pointer faster than the frames (as a mouse is: 125 Hz and more), through the
  // page's own pointer handlers: the frame rate the page reaches while dragging, apart from how fast the
  // test driver can hand over input (each move above is a round trip to the browser).
  const fast = await page.evaluate(async (ms) => {
    const p = window.pectus, canvas = p.scene.renderer.domElement, r = canvas.getBoundingClientRect();
    const x = r.left + r.width / 2, y = r.top + r.height / 2;
    const fire = (type, at) => canvas.dispatchEvent(new PointerEvent(type, { clientX: x, clientY: at, shiftKey: true, pointerId: 1, bubbles: true, isPrimary: true, buttons: 1 }));
    fire('pointerdown', y);
    const r0 = p.renders(), p0 = p.state.bar.position, t0 = performance.now();
    let i = 0;
    await new Promise((done) => {
      const timer = setInterval(() => {
        fire('pointermove', y - 40 + Math.abs((i++ % 160) - 80));
        if (performance.now() - t0 > ms) {
          clearInterval(timer);
          done();
        }
      }, 8);
    });
    const seconds = (performance.now() - t0) / 1000, frames = p.renders() - r0, moved = p.state.bar.position !== p0;
    fire('pointerup', y);
    return { seconds, pointer_moves: i, frames, fps: frames / seconds, bar_moved: moved };
  }, dragSeconds * 1000);
  const round = (o) => Object.fromEntries(Object.entries(o).map(([k, v]) => [k, typeof v === 'number' ? Math.round(v * 100) / 100 : v]));
  console.log(JSON.stringify({
    renderer,
    compositing: gpuCompositing ? 'gpu (SwiftShader)' : 'software',
    viewport,
    cpus: os.cpus().length,
    load_average: os.loadavg().map((v) => Math.round(v * 100) / 100),
    first_frame_ms: firsts.map((f) => Math.round(f.first_frame)),
    first_frame_median_ms: Math.round(median(firsts.map((f) => f.first_frame))),
    first_frame_steps_ms: firsts.map(round),
    frame_ms: { at_rest: round(atRest), moving: round(moving) },
    drag_driver: { seconds, pointer_moves: moves, frames: after.renders - before.renders, fps: (after.renders - before.renders) / seconds,
      bar_moved: after.position !== before.position },
    drag_125hz: fast,
    page_errors: errors,
  }, null, 1));
} finally {
  await context.close();
  fs.rmSync(userDataDir, { recursive: true, force: true });
}
