// The problems box ([data-testid=errors]): every problem as text (file, line, message), never as HTML.
import { state } from './state.js';

const box = () => document.getElementById('errors');

/** Lists problems [{ file, line, message }]; `heading` defaults to the one for a refused input. */
export function showProblems(problems, heading) {
  if (!problems.length) return box().replaceChildren();
  const head = document.createElement('strong');
  const serious = problems.some((p) => p.file !== null || p.line !== null || !/^ignored/.test(p.message));
  head.textContent = heading ?? (serious
    ? `${problems.length} problem${problems.length > 1 ? 's' : ''}${state.pop ? '; the previous population is kept' : ''}`
    : 'Note');
  const list = document.createElement('ul');
  for (const p of problems) {
    const li = document.createElement('li');
    if (p.file !== null && p.file !== undefined) {
      const f = document.createElement('span');
      f.className = 'file';
      f.textContent = p.file;
      li.append(f, p.line ? `, line ${p.line}: ` : ': ');
    }
    li.append(p.message);
    list.append(li);
  }
  box().replaceChildren(head, list);
}

/** One note (not a problem) in the box. */
export const note = (message) => showProblems([{ file: null, line: null, message }], 'Note');
