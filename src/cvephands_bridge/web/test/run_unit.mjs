// Runs the client's unit tests (test/*.test.mjs, node:test) and writes their results as one
// gtest-style <testsuite> (what catkin_test_results counts). Uses node:test's run() API, which
// Node 18 and 20 both have (node's own junit reporter is newer and writes bare <testcase>s).
// Without the npm packages (scripts/setup.sh runs npm ci) it records one skipped test saying so.
//   node test/run_unit.mjs RESULT.xml
import { existsSync, mkdirSync, readdirSync, writeFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { run } from 'node:test';
import { fileURLToPath } from 'node:url';

const out = process.argv[2];
if (!out) {
  console.error('usage: node test/run_unit.mjs RESULT.xml');
  process.exit(2);
}
const here = dirname(fileURLToPath(import.meta.url));
const xml = (s) => String(s).replace(/[<>&"]/g, (c) => `&#${c.charCodeAt(0)};`);
mkdirSync(dirname(out), { recursive: true });

function write(cases, skippedWhy = '') {
  const failures = cases.filter((c) => c.failure !== undefined).length;
  const body = skippedWhy
    ? `  <testcase name="web client unit tests" classname="web"><skipped message="${xml(skippedWhy)}"/></testcase>\n`
    : cases.map((c) => `  <testcase name="${xml(c.name)}" classname="web" time="${c.seconds}">` +
      (c.failure !== undefined ? `<failure message="${xml(c.failure)}"/>` : '') + '</testcase>\n').join('');
  writeFileSync(out, '<?xml version="1.0" encoding="utf-8"?>\n' +
    `<testsuite name="web_client" tests="${skippedWhy ? 1 : cases.length}" failures="${failures}" ` +
    `errors="0" skipped="${skippedWhy ? 1 : 0}">\n${body}</testsuite>\n`);
  return failures;
}

if (!existsSync(join(here, '..', 'node_modules', 'fzstd'))) {
  const why = 'npm packages not installed in web/node_modules (scripts/setup.sh runs npm ci)';
  write([], why);
  console.log(`[web unit tests] skipped: ${why}`);
  process.exit(0);
}

const files = readdirSync(here).filter((f) => f.endsWith('.test.mjs')).map((f) => join(here, f));
const cases = [];
const stream = run({ files });
stream.on('test:pass', (t) => {
  if (t.details && t.details.type === 'suite') return;
  cases.push({ name: t.name, seconds: ((t.details && t.details.duration_ms) || 0) / 1000 });
  console.log(`  ok   ${t.name}`);
});
stream.on('test:fail', (t) => {
  const err = t.details && t.details.error;
  const message = err ? (err.cause ? String(err.cause.message || err.cause) : String(err.message || err)) : 'failed';
  cases.push({ name: t.name, seconds: ((t.details && t.details.duration_ms) || 0) / 1000, failure: message });
  console.log(`  FAIL ${t.name}: ${message}`);
});
stream.on('test:diagnostic', () => {});
let finished = false;
stream.on('end', () => {
  if (finished) return;
  finished = true;
  const failures = write(cases);
  console.log(`[web unit tests] ${cases.length} tests, ${failures} failures -> ${out}`);
  process.exit(failures === 0 && cases.length > 0 ? 0 : 1);
});
// Older node:test streams emit 'close' rather than 'end' once drained.
stream.on('close', () => stream.emit('end'));
stream.resume();
