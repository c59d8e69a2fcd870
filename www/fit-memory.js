// What the worker keeps of the finished fits of the population shown, for the fits and questions after them:
//  - the parts and colours of the last FITS_REMEMBERED fits, the newest first: a new fit keeps the colour of
//    every part that is the same as one of theirs, the newest's first
//    (posemfa::articulate::graph::colour_parts_like), so fits compare by eye, and fits A, B, A show A alike;
//  - the merge tree the page's slider shows (wasm TreeCuts, posemfa::parts::merge_tree::TreeCuts): the last
//    finished fit's, kept through a Refine (a fit from one of its partitions), so that every count of the tree
//    the user chose from stays in reach after it, and a second Refine chooses from the same tree.
const FITS_REMEMBERED = 8;

export class FitMemory {
  constructor(paletteSize) {
    this.paletteSize = paletteSize;
    this.finals = []; // [{ labels, colours }]
    this.cuts = null;
    this.parents = false;
  }

  /** A new population: nothing of the last one's fits applies to it. */
  forget() {
    this.finals = [];
    this.dropTree();
  }

  dropTree() {
    this.cuts?.free();
    this.cuts = null;
    this.parents = false; // the tree is the one a Refine started from, not the model's own
  }

  /** Palette index of every part of `labels` (one per vertex): neighbouring parts differ (Rust's part graph).
   * A fit cancelled early has no coarse or refined labels yet (empty): no colours either. */
  colours(pop, labels) {
    return labels.length ? pop.partColours(labels, this.paletteSize) : new Uint32Array(0);
  }

  /** Colours like another partition's (its labels `like`, its colours) where a part is the same; plain colours
   * without one. */
  coloursLike(pop, labels, like, likeColours) {
    return labels.length && like?.length
      ? pop.partColoursLike(labels, this.paletteSize, like, likeColours) : this.colours(pop, labels);
  }

  /** Colours like the last finished fits' where a part is the same; a finished (`complete`) fit becomes the
   * newest to follow. */
  finalColours(pop, labels, complete) {
    const like = this.finals.filter((f) => f.labels.length === labels.length);
    const concat = (key) => Uint32Array.from(like.flatMap((f) => Array.from(f[key])));
    const colours = this.coloursLike(pop, labels, concat('labels'), concat('colours'));
    if (complete && labels.length) {
      this.finals = [{ labels: labels.slice(), colours: colours.slice() }, ...this.finals].slice(0, FITS_REMEMBERED);
    }
    return colours;
  }

  /** The finished model `m` becomes the one whose tree the slider shows, unless it was `refined` from a
   * partition of the tree kept: that tree stays. */
  keepTree(m, refined) {
    if (refined && this.cuts) {
      this.parents = true;
      return;
    }
    this.dropTree();
    this.cuts = m.treeCuts() ?? null;
  }

  /** A new fit that is no Refine starts: the tree goes while it runs (wasm memory: the new fit brings its own)
   * if the model shown can give it again (see `restoreTree`); a tree the model shown was refined from stays. */
  releaseTree() {
    if (!this.parents) this.dropTree();
  }

  /** The model `m` stays shown (the new fit was cancelled): its tree again, if it went. */
  restoreTree(m) {
    if (!this.cuts && m) this.keepTree(m, false);
  }

  /** {most, fewest, decided} of the tree kept, or null. */
  treeCounts() {
    return this.cuts?.counts() ?? null;
  }

  /** The kept tree's partition with n parts, coloured like the last fit's parts where a part is the same. */
  treePartition(pop, n) {
    if (!this.cuts) throw new Error('this fit has no merge tree (part rule tree only)');
    const labels = this.cuts.labels(n);
    return { labels, colours: this.coloursLike(pop, labels, this.finals[0]?.labels, this.finals[0]?.colours) };
  }
}
