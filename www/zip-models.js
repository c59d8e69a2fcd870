// A .zip holding a model file (.posemfa), as a paper's demo may serve its model and poses in one archive: the
// worker opens it through the core (src/mesh/zip_archive.rs, with its checks for zip bombs and damage) so that
// the model file is found among its entries. Any other archive goes to the population's loader as it is, which
// opens it the same way and says in the source which archive the poses came from.
const isZip = (name) => /\.zip$/i.test(name);

/** `data` ({ names, files: ArrayBuffer[] }) with every archive that holds a model file replaced by its entries. */
export function openModelZips(wasm, data) {
  if (!data.names.some(isZip)) return data;
  const names = [];
  const files = [];
  data.names.forEach((name, k) => {
    const bytes = new Uint8Array(data.files[k]);
    if (isZip(name) && wasm.zipHoldsModel(bytes)) {
      const opened = wasm.openZip(name, bytes);
      names.push(...opened.names);
      files.push(...opened.files.map((f) => f.buffer));
    } else {
      names.push(name);
      files.push(data.files[k]);
    }
  });
  return { ...data, names, files };
}
