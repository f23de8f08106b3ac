// The exercise's HMI (hub/run/exercise.py, the figures message's `exercise` section): the task,
// each goal with its state live (met, not yet, or judged at the end) and, once the run has ended,
// the score. What a trainee works from; the instructor's page shows it too.

import { formatNumber } from './figures.js';

function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  e.append(...children.filter((c) => c !== null && c !== undefined));
  return e;
}

const MARK = { true: ['✓', 'met'], false: ['✗', 'not met'], null: ['…', 'judged at the end'] };

export class ExercisePanel {
  constructor(box) {
    this.box = box;                  // the <details> of the exercise
    this.body = box.querySelector('#exercise');
    this.last = null;
  }

  /** @param {object|undefined} section the exercise section; `ended`: the run's last figures */
  update(section, ended) {
    if (!section || typeof section !== 'object') return;
    this.last = { ...section, ended: !!ended };
    this.box.hidden = false;
    const goals = (section.goals ?? []).map((g) => {
      const [mark, said] = MARK[String(g.met ?? null)] ?? MARK.null;
      return el('li', { class: `goal ${g.met === true ? 'met' : g.met === false ? 'unmet' : 'open'}`, 'data-goal': g.name },
        el('span', { class: 'goal-mark', title: said }, mark), ' ',
        el('b', {}, g.name), g.points !== 1 ? el('span', { class: 'muted' }, ` (${g.points} points)`) : null,
        el('div', { class: 'goal-measured muted' }, g.measured ?? ''));
    });
    const score = ended
      ? el('p', { id: 'exercise-score', class: section.passed ? 'passed' : 'failed' },
        `Score: ${formatNumber(section.score ?? 0)} % (${section.points} of ${section.total} points) — `,
        el('b', {}, section.passed ? 'passed' : 'failed'), ` (passes at ${formatNumber(section.pass ?? 100)} %)`)
      : el('p', { id: 'exercise-score', class: 'muted' }, 'The score is given when the run ends.');
    this.body.replaceChildren(el('p', { class: 'task' }, section.task ?? ''), el('ul', { class: 'goals' }, ...goals), score);
  }
}
