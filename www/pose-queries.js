// Pose mode's questions to the worker, merged into the worker's QUERIES: each asks the Rust core's
// Poser (src/export/pose_glb.rs, through src/wasm.rs) and returns plain data or typed arrays. The poser belongs
// to the model it was made from: a new model (or population) needs a new poseStart. getModel(): the worker's
// model; generation(): what changes whenever that model is replaced (by default the model object itself; the
// page's worker gives a number, because a model parked through a new fit and restored is the same model in a
// new wasm object).
export function poseQueries(getModel, generation = getModel) {
  let poser = null;
  let owner = null;
  let frameBones = null; // the last added frames' bones (12 numbers a bone, one Float64Array a frame)
  const current = () => {
    if (!poser || owner !== generation()) throw new Error('pose mode: the model changed; open pose mode again');
    return poser;
  };
  const posed = (p) => ({ positions: p.positions(), angles: p.angles() });
  // Runs `ask` with the poser set to added frame f (what the view shows while frames play or are paused on
  // one), then puts the pose made back: the exports and the sliders' coordinates of a frame come from the core
  // as those of a made pose do.
  const atFrame = (f, ask) => {
    const p = current();
    if (!frameBones) throw new Error('the added frames came without their bones from the core (src/wasm.rs Poser.addFrames gives them): rebuild the wasm (npm run build:wasm), then add the frames again');
    const bones = frameBones[f];
    if (!bones) throw new Error(`no added frame ${f + 1}: ${frameBones.length} frames were added`);
    const made = p.bones();
    p.setBones(bones);
    try {
      return ask(p);
    } finally {
      p.setBones(made);
    }
  };
  return {
    poseStart: (opts) => {
      poser?.free();
      poser = null;
      owner = generation();
      frameBones = null;
      poser = getModel().poser(opts ?? {});
      // coords: the rest pose's coordinates along the pose space's modes (what its sliders show); trainingAngles:
      // each bone's largest angle from the rest pose over the training poses (what a made pose is read against)
      return { skeleton: poser.skeleton(), ...posed(poser), coords: poser.poseVector().coords, trainingAngles: Array.from(poser.trainingAngles()) };
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
    // bone's angles from the rest pose in every training pose: at its joint, and its own (the core's two measures)
    poseTrainingAnglesOf: (bone) => {
      const r = current().trainingAnglesOf(bone);
      return { joint: r.joint, whole: r.whole };
    },
    poseTouches: (bone) => current().touches(bone),
    poseObj: (header) => current().objText(header),
    poseGlb: () => current().poseGlb(),
    poseAddFrames: (names, files) => {
      const p = current();
      // a frame of another mesh is refused by the core naming its file (src/articulate/pose.rs check_frame_sizes)
      const r = p.addFrames(names, files.map((b) => new Uint8Array(b)));
      frameBones = r.bones ?? null;
      delete r.bones; // they stay here (atFrame); bonesKept: the frames' exports and coordinates can be asked
      r.bonesKept = frameBones !== null;
      return r;
    },
    poseFrameVector: (f) => atFrame(f, (p) => p.poseVector()),
    poseFrameObj: (f, header) => atFrame(f, (p) => p.objText(header)),
    poseFrameGlb: (f) => atFrame(f, (p) => p.poseGlb()),
  };
}
