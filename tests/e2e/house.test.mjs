// The page's house rules (issue 10), read from the source in www/ (its generated www/pkg/ left out): no file
// over 400 lines, and no geometry in JS: the core computes positions, distances, part colourings and bounding
// boxes; the page only shows them. The only trigonometry or vector lengths allowed are the camera's (viewer.js:
// framing the view) and the pointer's (views/inspect.js: a click is a drag of at most 4 pixels).
// Run: node --test tests/e2e/house.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readdirSync, readFileSync } from 'node:fs';
import { join, relative, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

const ROOT = resolve(fileURLToPath(new URL('../..', import.meta.url)));
const WWW = join(ROOT, 'www');

function sources(dir = WWW, out = []) {
  for (const e of readdirSync(dir, { withFileTypes: true })) {
    const p = join(dir, e.name);
    if (e.isDirectory()) {
      if (relative(WWW, p) !== 'pkg') sources(p, out);
    } else if (/\.(js|mjs|html|css)$/.test(e.name)) {
      out.push(p);
    }
  }
  return out;
}

const MAX_LINES = 400;

test(`no file in www/ is over ${MAX_LINES} lines`, () => {
  const files = sources();
  assert.ok(files.length >= 20, `found only ${files.length} files in www/`);
  assert.ok(files.some((f) => f.endsWith(join('explain', 'figures.js'))), 'the article\'s figures were read');
  const long = files
    .map((f) => ({ file: relative(ROOT, f), lines: readFileSync(f, 'utf8').split('\n').length - 1 }))
    .filter((x) => x.lines > MAX_LINES);
  assert.deepEqual(long, []);
});

test('no geometry in www/: no trigonometry or vector lengths outside the camera and the pointer, no part colouring', () => {
  const allowed = new Set(['viewer.js', join('views', 'inspect.js')]);
  const geometry = /Math\.(sqrt|hypot|acos|asin|atan2?|cos|sin|tan|cbrt)\b|\bcolourParts\b|\bpartAdjacency\b|\bslerp\b|\blerp\(/;
  const found = [];
  let read = 0;
  for (const f of sources()) {
    const rel = relative(WWW, f);
    if (allowed.has(rel) || !/\.(js|mjs|html)$/.test(f)) continue;
    read++;
    readFileSync(f, 'utf8').split('\n').forEach((line, i) => {
      if (geometry.test(line.replace(/\/\/.*$/, ''))) found.push(`www/${rel}:${i + 1}: ${line.trim()}`);
    });
  }
  assert.ok(read >= 20, `read only ${read} files`);
  assert.deepEqual(found, []);
});
