// Runs the client's unit tests (test/*.test.mjs, node:test) and writes their results as one
// gtest-style <testsuite> (what catkin_test_results counts; node's own junit reporter writes
// bare <testcase>s under <testsuites>, which it does not).
//   node test/run_unit.mjs RESULT.xml
import { spawnSync } from 'node:child_process';
import { mkdirSync, readdirSync, readFileSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const out = process.argv[2];
if (!out) {
  console.error('usage: node test/run_unit.mjs RESULT.xml');
  process.exit(2);
}
const here = dirname(fileURLToPath(import.meta.url));
const files = readdirSync(here).filter((f) => f.endsWith('.test.mjs')).map((f) => join(here, f));
const raw = join(tmpdir(), `cvephands_web_unit_${process.pid}.xml`);
const r = spawnSync(process.execPath, ['--test', '--test-reporter=spec',
  '--test-reporter-destination=stdout', '--test-reporter=junit',
  `--test-reporter-destination=${raw}`, ...files], { stdio: ['ignore', 'inherit', 'inherit'] });
let body = '';
try {
  body = readFileSync(raw, 'utf8').replace(/^<\?xml[^>]*>\s*/, '').replace(/<\/?testsuites>/g, '');
} catch (e) {
  body = `<testcase name="run" classname="web"><failure message="no results: ${e.message}"/></testcase>`;
}
const count = (re) => (body.match(re) || []).length;
const tests = count(/<testcase\b/g);
const failures = count(/<failure\b/g);
const skipped = count(/<skipped\b/g);
mkdirSync(dirname(out), { recursive: true });
writeFileSync(out, '<?xml version="1.0" encoding="utf-8"?>\n' +
  `<testsuite name="web_client" tests="${tests}" failures="${failures}" errors="0" ` +
  `skipped="${skipped}">\n${body}</testsuite>\n`);
console.log(`[web unit tests] ${tests} tests, ${failures} failures, ${skipped} skipped -> ${out}`);
process.exit(r.status === 0 && failures === 0 && tests > 0 ? 0 : 1);
