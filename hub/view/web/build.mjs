// Bundles the view for `planthub view`: src/main.js (and the CSS it imports) into
// build/view/assets/, index.html into build/view/. Everything the page needs at run time is in
// the bundle — no CDN, so the view works offline. Paths are taken from this file's place, so the
// build works from any working directory.

import { build } from 'esbuild';
import { copyFile, mkdir, rm } from 'node:fs/promises';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const out = join(here, '..', '..', '..', 'build', 'view');
const assets = join(out, 'assets');

await rm(assets, { recursive: true, force: true });
await mkdir(assets, { recursive: true });
const result = await build({
  entryPoints: [join(here, 'src', 'main.js')],
  bundle: true,
  format: 'esm',
  target: ['es2022'],
  minify: true,
  sourcemap: true,
  legalComments: 'linked',
  outdir: assets,
  metafile: true,
  logLevel: 'warning',
});
await copyFile(join(here, 'index.html'), join(out, 'index.html'));

for (const [file, info] of Object.entries(result.metafile.outputs)) {
  if (!file.endsWith('.map')) console.log(`${file}  ${(info.bytes / 1024).toFixed(0)} kB`);
}
console.log(join(out, 'index.html'));
