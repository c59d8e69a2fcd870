// A question asked in the page, where the button was pressed, instead of the browser's confirm box (which a
// browser may suppress, and a script that drives the page may never answer: the button then looked dead). The
// box names what would be dropped and has two buttons; Yes resolves true, No resolves false and leaves a line
// saying what was kept, so that a "No" is seen to have done something. One question at a time: a new one answers
// the last No.
let open = null;

const button = (text, testid) => Object.assign(document.createElement('button'), { type: 'button', textContent: text, className: testid });

/** Asks `question` in a box placed after `anchor`; resolves true (yes) or false (no). `kept`: the line left
 * when the answer is No. */
export function ask(anchor, question, { yes = 'Yes', no = 'No', kept = 'Nothing was changed.' } = {}) {
  open?.settle(false);
  document.querySelectorAll('.ask').forEach((b) => b.remove());
  const box = document.createElement('div');
  box.className = 'ask';
  box.dataset.testid = 'ask';
  box.setAttribute('role', 'alertdialog');
  box.setAttribute('aria-label', question);
  const text = Object.assign(document.createElement('p'), { textContent: question });
  const y = button(yes, 'ask-yes');
  const n = button(no, 'ask-no');
  y.dataset.testid = 'ask-yes';
  n.dataset.testid = 'ask-no';
  const row = Object.assign(document.createElement('div'), { className: 'buttons' });
  row.append(y, n);
  box.append(text, row);
  anchor.after(box);
  box.scrollIntoView({ block: 'nearest' });
  y.focus({ preventScroll: true });
  return new Promise((resolve) => {
    const settle = (answer) => {
      if (open?.box !== box) return;
      open = null;
      if (answer) box.remove();
      else {
        // the No is seen: a line that says what stayed, until the next question
        box.setAttribute('role', 'status');
        box.classList.add('kept');
        box.replaceChildren(Object.assign(document.createElement('p'), { textContent: kept }));
      }
      resolve(answer);
    };
    open = { box, settle };
    y.addEventListener('click', () => settle(true));
    n.addEventListener('click', () => settle(false));
    box.addEventListener('keydown', (e) => e.key === 'Escape' && settle(false));
  });
}

/** Removes a question left open or a "kept" line (the state it spoke of has changed). */
export function clearAsk() {
  open?.settle(false);
  document.querySelectorAll('.ask').forEach((b) => b.remove());
}
