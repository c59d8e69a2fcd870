// Pose mode's questions to the worker (issue 28), merged into the worker's QUERIES: each asks the Rust core's
// Poser (src/export/pose_glb.rs, through src/wasm.rs) and returns plain data or typed arrays. The poser belongs
// to the model it was made from: a new model (or population) needs a new poseStart. getModel(): the worker's
// model; generation(): what changes whenever that model is replaced (by default the model object itself; the
// page's worker gives a number, because a model parked through a new fit and restored is the same model in a
// new wasm object).
export function poseQueries(getModel, generation = getModel) {
  let poser = null;
  let owner = null;
  const current = () => {
    if (!poser || owner !== generation()) throw new Error('pose mode: the model changed; open pose mode again');
    return poser;
  };
  const posed = (p) => ({ positions: p.positions(), angles: p.angles() });
  return {
    poseStart: (opts) => {
      poser?.free();
      poser = null;
      owner = generation();
      poser = getModel().poser(opts ?? {});
      return { skeleton: poser.skeleton(), ...posed(poser) };
    },
    poseTurn: (bone, axis, angle) => {
      const p = current();
      p.turn(bone, axis, angle);
      return posed(p);
    },
    poseSetBones: (bones) => {
      const p = current();
      p.setBones(Float64Array.from(bones));
      return posed(p);
    },
    poseBones: () => current().bones(),
    poseReset: () => {
      const p = current();
      p.reset();
      return posed(p);
    },
    poseModes: (coeffs) => {
      const p = current();
      p.setModes(Float64Array.from(coeffs));
      return posed(p);
    },
    poseTraining: (i) => {
      const p = current();
      p.setTraining(i);
      return posed(p);
    },
    poseRandom: (seed) => current().randomCoords(seed),
    poseVector: () => current().poseVector(),
    poseJoint: (bone) => current().jointPosition(bone),
    poseTouches: (bone) => current().touches(bone),
    poseObj: (header) => current().objText(header),
    poseGlb: () => current().poseGlb(),
    poseAddFrames: (names, files) => current().addFrames(names, files.map((b) => new Uint8Array(b))),
  };
}
