// Writes the encoded streams of this folder with meshoptimizer's own
// encoder: `npm install meshoptimizer@1.3.0` in an empty folder, then
// `node make.mjs` there writes them into ./fx/. src/scene/gltf/meshopt.rs
// decodes them and checks the values against the same formulas.
import { MeshoptEncoder as E } from 'meshoptimizer/encoder';
import fs from 'fs';
await E.ready;
fs.mkdirSync('fx', { recursive: true });
const out = (name, bytes) => fs.writeFileSync('fx/' + name, Buffer.from(bytes));
// ATTRIBUTES, no filter: 300 elements of 12 bytes, 2 blocks.
{
  const n = 300, s = 12, b = new Uint8Array(n * s);
  for (let i = 0; i < n; i++) for (let k = 0; k < s; k++) {
    b[i*s+k] = [i & 255, (i*i*31 + k*17 + (i>>3)) & 255, 0, ((i>>4)*5 + k) & 255][k % 4];
  }
  out('attributes.bin', E.encodeGltfBuffer(b, n, s, 'ATTRIBUTES'));
}
// TRIANGLES: an 8x8 grid in row order, then 20 scattered triangles.
function tris(off) {
  const t = [];
  for (let y = 0; y < 8; y++) for (let x = 0; x < 8; x++) {
    const v = y * 9 + x;
    t.push(v, v + 1, v + 10, v, v + 10, v + 9);
  }
  for (let k = 0; k < 20; k++) t.push((k*7) % 81 + off, (k*13 + 5) % 81 + off, (k*29 + 11) % 81 + off);
  return t;
}
out('triangles16.bin', E.encodeGltfBuffer(new Uint8Array(new Uint16Array(tris(0)).buffer), 148*3, 2, 'TRIANGLES'));
out('triangles32.bin', E.encodeGltfBuffer(new Uint8Array(new Uint32Array(tris(100000)).buffer), 148*3, 4, 'TRIANGLES'));
// INDICES: two interleaved runs.
{
  const ix = []; for (let i = 0; i < 100; i++) ix.push(i % 2 == 0 ? i / 2 : 1000 - i);
  out('indices.bin', E.encodeGltfBuffer(new Uint8Array(new Uint16Array(ix).buffer), 100, 2, 'INDICES'));
}
// Filters, 50 elements each.
const n = 50;
{
  const v = new Float32Array(n * 4);
  for (let i = 0; i < n; i++) {
    const a = i * 0.37, b = i * 0.21 + 0.3;
    v.set([Math.cos(a) * Math.sin(b), Math.sin(a) * Math.sin(b), Math.cos(b), 1], i * 4);
  }
  out('octahedral4.bin', E.encodeGltfBuffer(E.encodeFilterOct(v, n, 4, 8), n, 4, 'ATTRIBUTES'));
  out('octahedral8.bin', E.encodeGltfBuffer(E.encodeFilterOct(v, n, 8, 12), n, 8, 'ATTRIBUTES'));
}
{
  const v = new Float32Array(n * 4);
  for (let i = 0; i < n; i++) {
    const q = [Math.sin(i*0.3), Math.cos(i*0.7), Math.sin(i*1.1 + 1), Math.cos(i*0.5)];
    const l = Math.hypot(...q);
    v.set(q.map(x => x / l), i * 4);
  }
  out('quaternion.bin', E.encodeGltfBuffer(E.encodeFilterQuat(v, n, 8, 12), n, 8, 'ATTRIBUTES'));
}
{
  const v = new Float32Array(n * 3);
  for (let i = 0; i < n; i++) for (let k = 0; k < 3; k++) v[i*3+k] = (i - 25 + k * 0.5) * 3.7 * Math.pow(2, (i % 7) - 3);
  out('exponential.bin', E.encodeGltfBuffer(E.encodeFilterExp(v, n, 12, 15), n, 12, 'ATTRIBUTES'));
}
