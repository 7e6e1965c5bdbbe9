// Builds the browser client into dist/ (served by room_server --static DIR): bundles src/main.js
// with three.js and fzstd into one ES module, copies the page. Offline: everything comes from
// node_modules (npm ci against the committed package-lock.json).
import { build } from 'esbuild';
import { copyFileSync, mkdirSync, statSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const dist = join(here, 'dist');
mkdirSync(dist, { recursive: true });
await build({
  // The page and its worker (network, decoding, meshing: src/worker.js).
  entryPoints: { app: join(here, 'src', 'main.js'), worker: join(here, 'src', 'worker.js') },
  bundle: true,
  format: 'esm',
  minify: true,
  sourcemap: true,
  target: ['chrome100', 'firefox100', 'safari15'],
  outdir: dist,
  logLevel: 'warning',
});
for (const f of ['index.html', 'style.css']) copyFileSync(join(here, f), join(dist, f));
const kb = (f) => (statSync(join(dist, f)).size / 1024).toFixed(0);
console.log(`[web] client built in ${dist}: app.js ${kb('app.js')} kB, worker.js ${kb('worker.js')} kB`);
