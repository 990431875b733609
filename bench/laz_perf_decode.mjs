// Decodes every point of a LAZ file with the laz-perf npm package (LASzip compiled to
// WebAssembly) and prints points per second (best of 5), for bench/laz_bench.sh's side-by-side
// figure. Usage: node bench/laz_perf_decode.mjs FILE.laz   (laz-perf installed under bench/)
import { readFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import { basename } from 'node:path';

const require = createRequire(new URL('./node_modules/', import.meta.url));
const { createLazPerf } = require('laz-perf');

const file = process.argv[2];
const bytes = readFileSync(file);
const lazPerf = await createLazPerf();
const filePtr = lazPerf._malloc(bytes.length);
lazPerf.HEAPU8.set(bytes, filePtr);

let best = Infinity;
let count = 0;
for (let run = 0; run < 5; ++run) {
  const start = process.hrtime.bigint();
  const reader = new lazPerf.LASZip();
  reader.open(filePtr, bytes.length);
  count = reader.getCount();
  const pointPtr = lazPerf._malloc(reader.getPointLength());
  for (let i = 0; i < count; ++i) reader.getPoint(pointPtr);
  lazPerf._free(pointPtr);
  reader.delete();
  best = Math.min(best, Number(process.hrtime.bigint() - start) / 1e9);
}
lazPerf._free(filePtr);
console.log(`${basename(file).padEnd(28)} ${String(count).padStart(9)}  ${(count / best).toFixed(0).padStart(12)} pt/s (laz-perf)`);
