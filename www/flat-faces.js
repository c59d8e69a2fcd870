// "Flat colours" with one colour per triangle: with colours blended across a triangle, a low-poly
// character's large triangles that span two parts show a rainbow, and where a part ends can only be found by
// clicking. The flat material reads the colour of one vertex per triangle (GLSL `flat`: the provoking vertex,
// the first or the last by the GL implementation's convention), and each triangle's corners are put in an
// order (a rotation, so the winding stays) where the first and the last share the colour most of its corners
// have: whichever corner is read, a triangle shows its majority part's colour (its first corner's when all
// three differ). The order lives in a copy of the faces per mesh; picking reads the same corners.
import * as THREE from 'three';

/** The flat material: colours unlit, one per triangle. */
export function flatFacesMaterial() {
  const m = new THREE.MeshBasicMaterial({ vertexColors: true, side: THREE.DoubleSide });
  m.onBeforeCompile = (shader) => {
    shader.vertexShader = shader.vertexShader.replace('#include <color_pars_vertex>', 'flat varying vec4 vColor;');
    shader.fragmentShader = shader.fragmentShader.replace('#include <color_pars_fragment>', 'flat varying vec4 vColor;');
  };
  m.customProgramCacheKey = () => 'posemfa-flat-faces';
  return m;
}

const same = (c, a, b) => c[3 * a] === c[3 * b] && c[3 * a + 1] === c[3 * b + 1] && c[3 * a + 2] === c[3 * b + 2];

/** Orders the corners of every triangle of `geometry` (indexed by `faces`) for its colours, as the module says;
 * the geometry gets its own copy of the faces the first time. */
export function orderFaces(geometry, faces) {
  let index = geometry.getIndex();
  if (!index || index.array === faces || index.array.length !== faces.length) {
    index = new THREE.BufferAttribute(Uint32Array.from(faces), 1);
    geometry.setIndex(index);
  }
  const c = geometry.getAttribute('color').array;
  const out = index.array;
  for (let f = 0; f < faces.length; f += 3) {
    const a = faces[f];
    const b = faces[f + 1];
    const d = faces[f + 2];
    // the pair that shares a colour goes first and last: (a, b, d) keeps a..d, (b, d, a) b..a, (d, a, b) d..b
    if (same(c, a, b) && !same(c, a, d)) [out[f], out[f + 1], out[f + 2]] = [b, d, a];
    else if (same(c, b, d) && !same(c, a, b)) [out[f], out[f + 1], out[f + 2]] = [d, a, b];
    else [out[f], out[f + 1], out[f + 2]] = [a, b, d];
  }
  index.needsUpdate = true;
}
