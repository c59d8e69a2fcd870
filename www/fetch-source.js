// Opening from a URL (a link's src=URL, mount(element, { url })): a model file (.posemfa), a .zip of pose files,
// a .glb, or any one file the drop takes. Fetched with progress and Cancel; each way it can fail is said in
// words a person can act on: the address does not answer, the server answered 404, the server does not let
// this page read the file (CORS: which header it must send), the file is not one posemfa reads (what it looks
// like instead), or it is larger than the budget. What was loaded before stays.
import { filesFromBytes } from './drop.js';

/** The most bytes a link may bring (the budget of the wasm instance is 4 GiB; a population of 42 k vertices
 * x 49 poses with its model is 30 MB). */
export const URL_BUDGET = 1024 * 1024 * 1024;

const MB = (n) => `${(n / 1e6).toFixed(n < 1e7 ? 1 : 0)} MB`;

/** A refusal: `problems` as the page lists them. */
export class FetchProblem extends Error {
  constructor(url, message) {
    super(message);
    this.problems = [{ file: url, line: null, message }];
  }
}

/** What the first bytes say the file is: a known signature's extension, or null. */
function sniff(bytes) {
  const text = (n) => new TextDecoder('latin1').decode(bytes.subarray(0, n));
  if (text(8) === 'POSEMFA\0') return 'posemfa';
  if (text(4) === 'PK\u0003\u0004') return 'zip';
  if (text(4) === 'glTF') return 'glb';
  if (text(8) === 'PXR-USDC') return 'usdc';
  if (text(18) === 'Kaydara FBX Binary') return 'fbx';
  if (/^ply\r?\n/.test(text(5))) return 'ply';
  return null;
}

/** What a file that is not one posemfa reads looks like, for the message. */
function looksLike(bytes) {
  const head = new TextDecoder('utf-8', { fatal: false }).decode(bytes.subarray(0, 256)).trimStart().toLowerCase();
  if (head.startsWith('<!doctype html') || head.startsWith('<html')) return 'an HTML page (a server\'s error or index page?)';
  if (head.startsWith('{') || head.startsWith('[')) return 'JSON text (a posemfa JSON export is not read back: save a model file instead)';
  if (head.startsWith('<')) return 'XML or HTML text';
  return `bytes starting ${[...bytes.subarray(0, 8)].map((b) => b.toString(16).padStart(2, '0')).join(' ')}`;
}

const KNOWN = /\.(posemfa|zip|obj|ply|glb|gltf|vrm|fbx|usd|usda|usdc|usdz|pc2|mdd)$/i;

/**
 * Fetches `url` and returns what a drop gives ({ files, ignored, problems }, drop.js). Throws a FetchProblem
 * (or an AbortError when `signal` aborts). onProgress(received, total): total 0 when the server does not say.
 */
export async function fetchSource(url, { signal, onProgress = () => {}, budget = URL_BUDGET } = {}) {
  let abs;
  try {
    abs = new URL(url, location.href);
  } catch {
    throw new FetchProblem(String(url), `“${url}” is not a web address`);
  }
  if (!['http:', 'https:', 'blob:', 'data:'].includes(abs.protocol)) {
    throw new FetchProblem(abs.href, `a ${abs.protocol} address cannot be fetched by a page: give an http(s) address`);
  }
  const shown = abs.href;
  let res;
  try {
    res = await fetch(abs, { signal, credentials: 'omit' });
  } catch (e) {
    if (signal?.aborted) throw e;
    if (abs.origin !== location.origin && abs.protocol.startsWith('http')) {
      // A refusal by CORS and a server that is down look the same to a page; a request that asks to read nothing
      // (no-cors) tells them apart: it succeeds when the server answers.
      const answers = await fetch(abs, { mode: 'no-cors', signal, credentials: 'omit' }).then(() => true, () => false);
      if (answers) {
        throw new FetchProblem(shown, `the server ${abs.origin} answered, but does not let this page (${location.origin}) read the file: it must send the header “Access-Control-Allow-Origin: ${location.origin}” (or “*”) with it (see docs/embed.md), or the file must be put beside this page`);
      }
    }
    throw new FetchProblem(shown, `cannot be reached (${e.message}): check the address, and that the server is up`);
  }
  if (!res.ok) {
    const why = res.status === 404 ? ' (not found): check the address' : res.status === 403 ? ' (forbidden): the server does not give this file out' : `: the server could not give the file`;
    throw new FetchProblem(shown, `the server answered HTTP ${res.status} ${res.statusText}${why}`);
  }
  const total = Number(res.headers.get('content-length')) || 0;
  const over = (n) => new FetchProblem(shown, `the file is ${total ? '' : 'over '}${MB(n)}, more than the ${MB(budget)} a page opens from a link: open it from the disk (Open or a drop), or save its model without the poses`);
  if (total > budget) throw over(total);
  const chunks = [];
  let received = 0;
  const reader = res.body.getReader();
  for (;;) {
    const { done, value } = await reader.read();
    if (done) break;
    received += value.length;
    if (received > budget) {
      reader.cancel();
      throw over(received);
    }
    chunks.push(value);
    onProgress(received, total);
  }
  const bytes = new Uint8Array(received);
  let at = 0;
  for (const c of chunks) {
    bytes.set(c, at);
    at += c.length;
  }
  let name = decodeURIComponent(abs.pathname.split('/').pop() || '') || 'download';
  const kind = sniff(bytes);
  if (kind && !name.toLowerCase().endsWith(`.${kind}`) && !(kind === 'glb' && /\.vrm$/i.test(name))) name = `${name}.${kind}`;
  if (!kind && !KNOWN.test(name)) {
    throw new FetchProblem(shown, `not a file posemfa opens: it is ${looksLike(bytes)}; give the address of a model file (.posemfa), a .zip of pose files, a .glb or one of the mesh files a drop takes`);
  }
  if (!kind && /\.(posemfa|zip|glb)$/i.test(name)) {
    throw new FetchProblem(shown, `named like a .${name.split('.').pop()} file, but it is ${looksLike(bytes)}: the server may have sent an error page instead`);
  }
  return filesFromBytes(name, bytes);
}
