// Downloads of what the page made, and the population's name that starts every file's name: two populations'
// exports (or a pose made on each) do not overwrite each other in the downloads folder.
import { state } from './state.js';

/** Saves `data` as a file called `name` (the browser's download). */
export function download(name, data, type) {
  const url = URL.createObjectURL(new Blob([data], { type }));
  const a = Object.assign(document.createElement('a'), { href: url, download: name });
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}

/** `s` as a piece of a file name: a mesh file's extension dropped, every run of other characters one `_`. */
export const safeName = (s) => s.replace(/\.(obj|ply|glb|gltf|fbx|usd[acz]?|pc2|mdd|zip|posemfa)$/i, '').replace(/[^A-Za-z0-9._-]+/g, '_');

/** The population's name in file names: the example's id, the generator and its seed, or what the files'
 * names share (horse1.obj ... horse11.obj: "horse"); when they share nothing (1.obj ... 11.obj), their folder's
 * name (a folder or .zip dropped), else "population". */
export function populationStem() {
  const src = state.source;
  if (!src) return 'population';
  if (src.example) return src.example.id;
  if (src.spec) return `${src.spec.preset}-seed${src.spec.seed ?? 0}`;
  const paths = src.names ?? [];
  const names = paths.map((n) => safeName(n.split('/').pop()));
  if (names.length === 1) return names[0];
  let common = names[0] ?? '';
  for (const n of names) while (!n.startsWith(common)) common = common.slice(0, -1);
  common = common.replace(/[-_. 0-9]+$/, '');
  const folder = paths[0]?.split('/').slice(-2, -1)[0];
  return common || (folder ? safeName(folder) : 'population');
}
