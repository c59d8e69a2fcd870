// Opening files: the file and folder pickers and drops anywhere on the page. Turns what a person drops or
// picks (mesh files, folders, .zip archives) into [{ name, bytes }] for the worker. Nothing is parsed or
// unpacked here: the Rust readers pick themselves by extension (mesh::load: OBJ and PLY per pose, a .glb /
// .gltf with its .bin buffers, a .pc2 / .mdd point cache with its base mesh, an .fbx, a .usd / .usda / .usdc /
// .usdz) and validate the files, and a .zip is opened by the core as the CLI opens one (mesh/zip_archive.rs:
// zip bombs refused before anything is unpacked; www/zip-models.js for an archive holding a model file).

const collator = new Intl.Collator(undefined, { numeric: true, sensitivity: 'base' });
export const naturalSort = (items) => items.sort((a, b) => collator.compare(a.name, b.name));

// Files the core reads (src/mesh/load.rs, FileKind::is_known_extension, and model files: src/model_file.rs);
// images and .mtl files are not read.
export const isMeshFile = (name) => /\.(obj|ply|glb|gltf|vrm|bin|pc2|mdd|fbx|usd|usda|usdc|usdz|posemfa)$/i.test(name);
const isZip = (name) => /\.zip$/i.test(name);
const skip = (name) => /(^|\/)(__MACOSX\/|\.)/.test(name); // resource forks and hidden files

// One File -> entries: a mesh file or an archive as is, anything else reported as ignored.
async function fromFile(file, name, out) {
  if (isMeshFile(name) || isZip(name)) {
    out.files.push({ name, bytes: new Uint8Array(await file.arrayBuffer()) });
  } else if (!skip(name)) {
    out.ignored.push(name);
  }
}

/** The files of `bytes` named `name` (a mesh or model file or a .zip, as it is), as a drop gives them. */
export async function filesFromBytes(name, bytes) {
  const out = emptyResult();
  await fromFile(new Blob([bytes]), name, out);
  naturalSort(out.files);
  return out;
}

const fileOf = (entry) => new Promise((resolve, reject) => entry.file(resolve, reject));

// Chromium returns at most 100 entries per readEntries call: call it until it returns nothing.
async function readAll(reader) {
  const all = [];
  for (;;) {
    const batch = await new Promise((resolve, reject) => reader.readEntries(resolve, reject));
    if (batch.length === 0) return all;
    all.push(...batch);
  }
}

async function walk(entry, out) {
  const name = entry.fullPath.replace(/^\//, '');
  if (entry.isDirectory) {
    for (const child of await readAll(entry.createReader())) await walk(child, out);
  } else if (entry.isFile) {
    await fromFile(await fileOf(entry), name, out);
  }
}

const emptyResult = () => ({ files: [], ignored: [], problems: [] });

/** Files of a drop: folders walked through webkitGetAsEntry, zips opened; natural-sorted by name. */
export async function filesFromDataTransfer(dt) {
  const out = emptyResult();
  // Entries must be taken synchronously, before the first await: the DataTransfer empties afterwards.
  const entries = [...(dt.items || [])].filter((i) => i.kind === 'file').map((i) => i.webkitGetAsEntry?.());
  if (entries.length && entries.every(Boolean)) {
    for (const e of entries) await walk(e, out);
  } else {
    for (const f of dt.files) await fromFile(f, f.webkitRelativePath || f.name, out);
  }
  naturalSort(out.files);
  return out;
}

/** Files of an <input type=file> (multiple files, or a folder with webkitdirectory). */
export async function filesFromList(list) {
  const out = emptyResult();
  for (const f of list) await fromFile(f, f.webkitRelativePath || f.name, out);
  naturalSort(out.files);
  return out;
}

/** Wires the pickers (#file-input, #folder-input) and drops on the window to `open(promise of files)`. */
export function installDrop(open) {
  const $ = (id) => document.getElementById(id);
  for (const id of ['file-input', 'folder-input']) {
    $(id).addEventListener('change', (e) => {
      open(filesFromList([...e.target.files])); // a copy: clearing the input empties its FileList
      e.target.value = '';
    });
  }
  let dragDepth = 0;
  window.addEventListener('dragenter', (e) => {
    e.preventDefault();
    dragDepth++;
    $('drop-overlay').hidden = false;
  });
  window.addEventListener('dragleave', () => {
    if (--dragDepth <= 0) {
      dragDepth = 0;
      $('drop-overlay').hidden = true;
    }
  });
  window.addEventListener('dragover', (e) => e.preventDefault());
  window.addEventListener('drop', (e) => {
    e.preventDefault();
    dragDepth = 0;
    $('drop-overlay').hidden = true;
    open(filesFromDataTransfer(e.dataTransfer));
  });
}
