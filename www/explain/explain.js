// The article's entry (explain.html). It starts the one worker pool first, so that the workers fetch and
// compile the wasm module while the rest of the article (three.js, KaTeX, the figures: a separate chunk) is
// still being fetched and evaluated.
import { Pool } from './pool.js';

const pool = new Pool();
import('./article.js').then(({ start }) => start(pool));
