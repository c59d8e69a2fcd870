// The article's live figures, by the name in each figure element's data-figure (article.js makes them). Each is
// a few mount() views (www/mount.js) on the shared worker pool (www/explain/pool.js), each on its own small
// generated population; the scaffolding they share is in figure.js (and stepping.js for AECM step by step), the
// figures themselves in one module per section or pair of sections.
import { QUAD, BLOB, SYNTH } from './figure.js';
import { Poses, Model } from './fig-model.js';
import { Responsibilities, Aecm } from './fig-aecm.js';
import { Eq18, Ends } from './fig-paper.js';
import { Hierarchy, Reconstruction } from './fig-hierarchy.js';
import { Interpolation, Limit } from './fig-interp.js';
import { PoseSpace } from './fig-pose.js';

export const FIGURES = {
  poses: (ctx) => new Poses(ctx),
  model: (ctx) => new Model(ctx),
  responsibilities: (ctx) => new Responsibilities(ctx),
  aecm: (ctx) => new Aecm(ctx),
  eq18: (ctx) => new Eq18(ctx),
  ends: (ctx) => new Ends(ctx),
  hierarchy: (ctx) => new Hierarchy(ctx),
  reconstruction: (ctx) => new Reconstruction(ctx),
  interpolation: (ctx) => new Interpolation(ctx),
  posespace: (ctx) => new PoseSpace(ctx),
  // the app's "two legs that always move together" example (its tied front legs), on a smaller mesh
  tied: (ctx) => new Limit(ctx, ({ examples }) => ({ ...examples.find((e) => e.id === 'too-few-poses').spec, vertices: QUAD.vertices }), { ...SYNTH }),
  blob: (ctx) => new Limit(ctx, BLOB, { ...SYNTH, parts: 4 }),
};
