// The page's one three.js viewer (viewer.js) in #view, and its log-likelihood plot (plot.js) in #plot.
import { Viewer } from '../viewer.js';
import { Plot } from '../plot.js';

export const viewer = new Viewer(document.getElementById('view'));
export const plot = new Plot(document.getElementById('plot'));
