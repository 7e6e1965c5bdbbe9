// End-to-end check of the room client in a real browser: headless Debian Chromium (driven by
// playwright-core) opens the page of a running room server, waits until every expected
// participant shows both hands, measures the render rate and the end-to-end latency (capture
// stamp -> render) the page reports, saves a screenshot and checks it for skin-coloured pixels
// inside each hand's projected box.
//
//   node test/e2e_browser.mjs --url http://127.0.0.1:8765/ [--participants 2] [--hands 2]
//        [--timeout 90] [--measure 5] [--out DIR] [--chromium /usr/bin/chromium]
//        [--min-fps 5] [--max-latency 1000] [--faces 1 (0: no face video expected)]
//
// Prints one JSON object (the measurements and "failures": [...]) on stdout; exit status 0 when
// there are no failures, 1 otherwise, 2 when the browser cannot be started.
import { chromium } from 'playwright-core';
import { mkdirSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';

function parseArgs(argv) {
  const a = { url: 'http://127.0.0.1:8765/', participants: 2, hands: 2, timeout: 90, measure: 5,
    out: '', chromium: '/usr/bin/chromium', minFps: 5, maxLatency: 1000, faces: 1 };
  for (let i = 2; i < argv.length; i += 2) {
    const key = argv[i].replace(/^--/, '').replace(/-([a-z])/g, (_, c) => c.toUpperCase());
    if (!(key in a) || i + 1 >= argv.length) {
      console.error(`e2e_browser: bad argument ${argv[i]}`);
      process.exit(2);
    }
    a[key] = typeof a[key] === 'number' ? Number(argv[i + 1]) : argv[i + 1];
  }
  return a;
}

const args = parseArgs(process.argv);
const log = (...m) => console.error('[e2e_browser]', ...m);
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// Skin: the hand materials' tones under the room's lights are red-dominant and warm; the table,
// floor and background are blue-grey (b >= r), the labels white or grey.
function isSkin(r, g, b) {
  return r >= 80 && r > g && g > b && r - b >= 35;
}

let browser;
try {
  browser = await chromium.launch({
    executablePath: args.chromium,
    headless: true,
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
      '--enable-unsafe-swiftshader', '--use-angle=swiftshader'],
  });
} catch (e) {
  console.log(JSON.stringify({ failures: [`cannot start ${args.chromium}: ${e.message}`] }));
  process.exit(2);
}

const result = { url: args.url, failures: [] };
const consoleErrors = [];
try {
  const page = await browser.newPage({ viewport: { width: 960, height: 540 } });
  page.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(m.text()); });
  page.on('pageerror', (e) => consoleErrors.push(String(e)));
  // The room server may still be starting (a launch file starts everything at once).
  for (let attempt = 0; ; ++attempt) {
    try {
      await page.goto(args.url, { waitUntil: 'load', timeout: 20000 });
      break;
    } catch (e) {
      if (attempt >= 40) throw e;
      await sleep(500);
    }
  }
  log(`page loaded from ${args.url}, waiting for ${args.participants} participants with ` +
    `${args.hands} hands each (timeout ${args.timeout} s)`);

  const t0 = Date.now();
  let stats = null;
  let lastPrint = 0;
  const ready = (s) => {
    const rigs = s.participants.filter((p) => p.role === 'rig');
    // Faces too (when expected): a starved machine shows the hands before the first face
    // picture, and the screenshot's checks need both.
    return rigs.length >= args.participants &&
      rigs.every((p) => p.hands >= args.hands && (!args.faces || p.facesShown > 0));
  };
  for (;;) {
    stats = await page.evaluate(() => (window.cve ? window.cve.stats() : null));
    if (stats && ready(stats)) break;
    if (Date.now() - t0 > args.timeout * 1000) {
      result.failures.push(`not all hands appeared within ${args.timeout} s: ` +
        JSON.stringify(stats && stats.participants));
      break;
    }
    if (Date.now() - lastPrint > 5000) {
      lastPrint = Date.now();
      log(stats ? `${stats.state}: ${stats.participants.map((p) => `${p.name} ${p.hands} hand(s)`).join(', ')}`
        : 'page not running yet');
    }
    await sleep(250);
  }
  result.handsAfterS = (Date.now() - t0) / 1000;
  if (!result.failures.length) {
    log(`all hands after ${result.handsAfterS.toFixed(1)} s; measuring for ${args.measure} s`);
    const m0 = { frames: stats.framesRendered, t: Date.now() };
    await sleep(args.measure * 1000);
    const m1 = await page.evaluate(() => window.cve.stats());
    // Frames drawn over the whole measuring period (the page's own figure covers only 3 s, which
    // holds no frame at all below 0.33 fps).
    result.renderFpsMeasured = (m1.framesRendered - m0.frames) / ((Date.now() - m0.t) / 1000);
    // Both hands of every participant at one instant (a hand may be lost for a moment).
    const t1 = Date.now();
    let boxes = [];
    let faceBoxes = [];
    let shot = null;
    for (;;) {
      // Hold the hands still so that the boxes, the stats and the screenshot show one frame.
      await page.evaluate(() => window.cve.freeze(true));
      stats = await page.evaluate(() => window.cve.stats());
      boxes = await page.evaluate(() => window.cve.handScreenBoxes());
      faceBoxes = await page.evaluate(() => window.cve.faceScreenBoxes());
      shot = await page.screenshot({ type: 'png' });
      await page.evaluate(() => window.cve.freeze(false));
      if (ready(stats) && boxes.length >= args.participants * args.hands) break;
      if (Date.now() - t1 > 30000) {
        result.failures.push('no screenshot with every hand on screen within 30 s');
        break;
      }
      await sleep(200);
    }
    if (args.out) {
      mkdirSync(args.out, { recursive: true });
      result.screenshot = join(args.out, 'browser_room.png');
      writeFileSync(result.screenshot, shot);
    }
    // Decode the screenshot in the page itself (no PNG library needed) and count skin pixels
    // inside each hand's box and in the rest of the image.
    const dataUrl = `data:image/png;base64,${shot.toString('base64')}`;
    const hud = await page.evaluate(() => {
      const r = document.getElementById('hud').getBoundingClientRect();
      return { x0: r.left, y0: r.top, x1: r.right, y1: r.bottom };
    });
    const skin = await page.evaluate(async ({ dataUrl, boxes, faceBoxes, hud, isSkinSrc }) => {
      const isSkinFn = new Function(`return (${isSkinSrc})`)();
      const img = new Image();
      img.src = dataUrl;
      await img.decode();
      const c = document.createElement('canvas');
      c.width = img.width;
      c.height = img.height;
      const g = c.getContext('2d');
      g.drawImage(img, 0, 0);
      const px = g.getImageData(0, 0, c.width, c.height).data;
      const scale = img.width / window.innerWidth;
      const inBox = new Uint8Array(c.width * c.height);
      // Pixels under the status panel show the panel, not the room.
      const underHud = (x, y) => x >= hud.x0 * scale && x < hud.x1 * scale && y >= hud.y0 * scale &&
        y < hud.y1 * scale;
      // The face video planes show skin too: counted on their own, not as stray skin.
      const inFace = new Uint8Array(c.width * c.height);
      const perFace = faceBoxes.map((b) => {
        const x0 = Math.max(0, Math.floor(b.x0 * scale)), x1 = Math.min(c.width, Math.ceil(b.x1 * scale));
        const y0 = Math.max(0, Math.floor(b.y0 * scale)), y1 = Math.min(c.height, Math.ceil(b.y1 * scale));
        let n = 0, s = 0;
        for (let y = y0; y < y1; ++y) {
          for (let x = x0; x < x1; ++x) {
            const i = y * c.width + x;
            inFace[i] = 1;
            if (underHud(x, y)) continue;
            ++n;
            if (isSkinFn(px[4 * i], px[4 * i + 1], px[4 * i + 2])) ++s;
          }
        }
        return { ...b, pixels: n, skinFraction: n ? s / n : 0 };
      });
      const perBox = boxes.map((b) => {
        const x0 = Math.max(0, Math.floor(b.x0 * scale)), x1 = Math.min(c.width, Math.ceil(b.x1 * scale));
        const y0 = Math.max(0, Math.floor(b.y0 * scale)), y1 = Math.min(c.height, Math.ceil(b.y1 * scale));
        let n = 0, s = 0, hidden = 0;
        for (let y = y0; y < y1; ++y) {
          for (let x = x0; x < x1; ++x) {
            const i = y * c.width + x;
            inBox[i] = 1;
            if (underHud(x, y)) {
              ++hidden;
              continue;
            }
            ++n;
            if (isSkinFn(px[4 * i], px[4 * i + 1], px[4 * i + 2])) ++s;
          }
        }
        return { ...b, pixels: n, hiddenPixels: hidden, skinPixels: s, skinFraction: n ? s / n : 0 };
      });
      let outside = 0, outsideSkin = 0;
      for (let i = 0; i < c.width * c.height; ++i) {
        if (inBox[i] || inFace[i] || underHud(i % c.width, Math.floor(i / c.width))) continue;
        ++outside;
        if (isSkinFn(px[4 * i], px[4 * i + 1], px[4 * i + 2])) ++outsideSkin;
      }
      return { perBox, perFace, outsideSkinFraction: outside ? outsideSkin / outside : 0 };
    }, { dataUrl, boxes, faceBoxes, hud, isSkinSrc: isSkin.toString() });
    result.faces = skin.perFace;
    for (const f of skin.perFace) {
      // The face fills the middle of its picture (94 % skin there in test_face_video).
      if (f.pixels > 100 && f.skinFraction < 0.1) {
        result.failures.push(`participant ${f.participant}: the face plane shows ` +
          `${(100 * f.skinFraction).toFixed(1)} % skin`);
      }
    }
    result.hands = skin.perBox;
    result.outsideSkinFraction = skin.outsideSkinFraction;
    for (const b of skin.perBox) {
      // A hand fills 15-50 % of its screen box (a pointing hand least); a hand that is not drawn
      // leaves < 1 % (measured: 0.7 % when the status panel covered it). 5 % separates the two.
      if (b.hiddenPixels > b.pixels) {
        result.failures.push(`participant ${b.participant} hand ${b.target}: mostly under the ` +
          'status panel (the default view should frame the hands)');
      } else if (b.skinFraction < 0.05) {
        result.failures.push(`participant ${b.participant} hand ${b.target}: only ` +
          `${(100 * b.skinFraction).toFixed(1)} % skin pixels in its box`);
      }
    }
    if (skin.outsideSkinFraction > 0.002) {
      result.failures.push(`skin-coloured pixels outside the hands: ` +
        `${(100 * skin.outsideSkinFraction).toFixed(2)} %`);
    }
  }
  result.stats = stats;
  if (stats) {
    result.renderFps = stats.renderFps;
    result.latencyMs = stats.latencyMs;
    const fps = Math.max(stats.renderFps, result.renderFpsMeasured || 0);
    if (!(fps >= args.minFps)) {
      result.failures.push(`render rate ${fps.toFixed(2)} fps < ${args.minFps}`);
    }
    // No latency sample in the page's 3 s window happens when it renders below ~1 fps (a
    // starved machine): that is reported, not failed; a measured latency above the bar fails.
    if (!(stats.latencyMs.count > 0)) {
      result.notes = (result.notes || []).concat(['no capture->render latency sample in the last 3 s']);
    } else if (!(stats.latencyMs.median <= args.maxLatency)) {
      result.failures.push(`end-to-end latency median ${stats.latencyMs.median} ms > ${args.maxLatency} ms`);
    }
    for (const p of stats.participants.filter((q) => q.role === 'rig')) {
      if (p.errors) result.failures.push(`${p.name}: ${p.errors} undecodable messages (${p.lastError})`);
      if (args.faces && !(p.facesShown > 0)) result.failures.push(`${p.name}: no face picture shown`);
      if (p.badFaces) result.failures.push(`${p.name}: ${p.badFaces} malformed face messages`);
    }
  }
} catch (e) {
  result.failures.push(`browser session failed: ${e.message}`);
} finally {
  result.consoleErrors = consoleErrors;
  if (consoleErrors.length) result.failures.push(`console errors: ${consoleErrors.slice(0, 3).join(' | ')}`);
  await browser.close();
}
console.log(JSON.stringify(result));
process.exit(result.failures.length ? 1 : 0);
