// The worker's questions (www/worker.js, `query` messages), by what they need: the model (QUERIES), the
// population with or without a model (POPULATION_QUERIES), or neither (FREE_QUERIES). Each returns plain data or
// typed arrays. `shown`: a mesh descriptor ({kind: 'pose' | 'linear' | ..., see Shown in src/export/shown.rs}).
// get: { wasm, model(), population(), memory (fit-memory.js), generation() (bumped when the model is replaced) }.
import { poseQueries } from './pose-queries.js';

export function workerQueries({ wasm, model, population, memory, generation }) {
  const POPULATION_QUERIES = {
    linearInterpolate: (i, j, t) => (model() ?? population()).linearInterpolate(i, j, t),
    objText: (shown, header) => (model() ?? population()).objText(shown, header),
    objScene: (meshes, header) => (model() ?? population()).objScene(meshes, header),
    originalLengths: (values) => population().originalLengths(Float64Array.from(values)),
  };
  const QUERIES = {
    reconstruct: (i) => model().reconstruct(i),
    latentPlaced: (i) => model().latentPlaced(i),
    vertexErrors: (i) => model().vertexErrors(i),
    responsibilities: (v) => model().responsibilities(v),
    rotationAngles: (part, ref) => model().rotationAngles(part, ref),
    toJson: () => model().toJson(),
    save: (withPoses) => model().save(!!withPoses), // the model file (.posemfa)
    interpolate: (i, j, t, opts) => model().interpolate(i, j, t, opts ?? {}),
    rig: (opts) => model().rig(opts ?? {}),
    articulationReport: (i, j, t) => model().articulationReport(i, j, t),
    // the merge tree's partition with n parts, coloured like the fitted parts where a part is the same
    treePartition: (n) => memory.treePartition(population(), n),
    ...poseQueries(model, generation), // pose mode: www/pose-queries.js
  };
  // the fit form's and the rig panel's fields, checked by the core
  const FREE_QUERIES = {
    formParams: (base, fields, vertices) => wasm.formParams(base, fields, vertices ?? undefined),
    rigFields: (fields) => wasm.rigFields(fields),
  };
  return { POPULATION_QUERIES, QUERIES, FREE_QUERIES };
}
