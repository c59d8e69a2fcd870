// The page's house rules (issue 10), read from the source in www/ (its generated www/pkg/ left out): no file
// over 400 lines, and no geometry in JS: the core computes positions, distances, part colourings and bounding
// boxes; the page only shows them. The only trigonometry or vector lengths allowed are the camera's (viewer.js:
// framing the view) and the pointer's (views/inspect.js: a click is a drag of at most 4 pixels).
// Run: node --test tests/e2e/house.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readdirSync, readFileSync } from 'node:fs';
import { dirname, join, relative, resolve } from 'node:path';
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

// Imports in www/ go one way (a cycle makes the load order, and so what is defined when, depend on which file
// is imported first). Every static `import ... from './x.js'` (and `import './x.js'`) of a
// www/ JS file to another www/ file is an edge; a cycle (a module that, through its imports, imports itself)
// fails with the cycle's files in order.
export function importGraph(files = sources().filter((f) => /\.(js|mjs)$/.test(f))) {
  const graph = new Map();
  for (const f of files) {
    const text = readFileSync(f, 'utf8');
    const deps = [];
    for (const m of text.matchAll(/^\s*(?:import|export)\s+(?:[^'";]*?\s+from\s+)?['"](\.{1,2}\/[^'"]+)['"]/gm)) {
      const target = resolve(dirname(f), m[1].replace(/\?.*$/, ''));
      if (target.startsWith(WWW) && !relative(WWW, target).startsWith('pkg')) deps.push(target);
    }
    graph.set(f, deps);
  }
  return graph;
}

export function findCycle(graph) {
  const state = new Map(); // 1: on the path, 2: done
  const path = [];
  const visit = (f) => {
    state.set(f, 1);
    path.push(f);
    for (const d of graph.get(f) ?? []) {
      if (state.get(d) === 1) return [...path.slice(path.indexOf(d)), d];
      if (!state.has(d)) {
        const c = visit(d);
        if (c) return c;
      }
    }
    path.pop();
    state.set(f, 2);
    return null;
  };
  for (const f of graph.keys()) {
    if (!state.has(f)) {
      const c = visit(f);
      if (c) return c.map((x) => `www/${relative(WWW, x)}`);
    }
  }
  return null;
}

test('www/ has no import cycle', () => {
  const graph = importGraph();
  const edges = [...graph.values()].reduce((a, d) => a + d.length, 0);
  assert.ok(graph.size >= 20 && edges >= 40, `read ${graph.size} files, ${edges} imports`);
  // the check itself finds a cycle where there is one
  const a = join(WWW, 'a.js');
  const b = join(WWW, 'b.js');
  assert.deepEqual(findCycle(new Map([[a, [b]], [b, [a]]])), ['www/a.js', 'www/b.js', 'www/a.js']);
  assert.equal(findCycle(new Map([[a, [b]], [b, []]])), null);
  assert.equal(findCycle(graph), null);
});
