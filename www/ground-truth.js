// A generated population's ground truth as words: the fit's accuracy against it, and the parts the generator
// moved alike (the "two legs that always move together" example). The figures come from the core
// (posemfa::metrics::ground_truth_accuracy); the app's result panel and the article both show them from here.

/** One line of ground-truth accuracy: adjusted Rand index and rotation error (median and worst part); '–' without
 * a ground truth. */
export function accuracyText(g) {
  if (!g) return '–';
  // one true part (the blob): every labelling scores 0, which says nothing about the fit
  if (g.trueParts < 2) return `one true part, so no adjusted Rand index (every labelling scores 0 against one part); rotation error ${g.rotationErrorDeg.toFixed(2)}° against each pose's best rigid fit`;
  return `adjusted Rand ${g.ari.toFixed(3)}; rotation error ${g.rotationErrorDeg.toFixed(2)}° median, ${g.rotationErrorDegMax.toFixed(2)}° worst part (${g.trueParts} true part${g.trueParts === 1 ? '' : 's'})`;
}

const words = (name) => name.replaceAll('_', ' ');

/** What the fit made of the true parts the generator moved alike (`groundTruth.tied`: one entry per pair, with
 * the fitted parts holding them and how far apart their motions are); '' when nothing was tied. */
export function tiedText(g) {
  const tied = g?.tied ?? [];
  if (!tied.length) return '';
  const apart = tied.filter((t) => t.fitted[0] !== t.fitted[1]);
  const joined = tied.length - apart.length;
  const pairs = (list, f) => list.map(f).join('; ');
  let text = '';
  if (apart.length) {
    const gap = Math.max(...apart.map((t) => t.motionGapDeg));
    const turn = Math.min(...apart.map((t) => t.turnDeg));
    const each = apart.length === 1 ? 'the pair' : `each of the ${apart.length} pairs`;
    text = `The tied parts: in ${each} (${pairs(apart, (t) => `${words(t.names[0])} and ${words(t.names[1])}`)}) the fit's two parts ` +
      `(${pairs(apart, (t) => `${t.fitted[0] + 1} and ${t.fitted[1] + 1}`)}) have motions that agree within ${gap.toFixed(2)}° (RMS over the poses) ` +
      `while they turn ${turn.toFixed(1)}° or more: motion cannot tell them apart, and they stay two parts only because they do not touch.`;
  }
  if (joined) {
    text += `${text ? ' ' : ''}${joined === tied.length ? 'The' : 'Of the'} tied pair${tied.length === 1 ? '' : 's'}, ${joined} ${joined === 1 ? 'is' : 'are'} one fitted part shared by both sides: ` +
      pairs(tied.filter((t) => t.fitted[0] === t.fitted[1]), (t) => `${words(t.names[0])} and ${words(t.names[1])} in part ${t.fitted[0] + 1}`) + '.';
  }
  return text;
}
