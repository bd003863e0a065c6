// SPDX-License-Identifier: MIT
// The change report turned into what a renderer uploads (shared by three.js's PMZStream on the
// page and worker.js): ranges of render vertices and faces. A render vertex is a position
// vertex, or with attributes (format 8.0) an attribute wedge as in the native viewer: then the
// positions are the wedges' positions, the indices the wedge indices, and the texture
// coordinates, normals and colours go along per wedge.
const NONE = 0xffffffff;

// [name, floats per render vertex] of the per-wedge attributes the stream has, three.js's
// attribute names (uv, uv1: texture coordinate sets 0 and 1).
export function attributeLayout(d) {
  if (!d.wedgeCount) return [];
  const layout = [];
  if (d.texcoordSetCount > 0) layout.push(['uv', 2]);
  if (d.texcoordSetCount > 1) layout.push(['uv1', 2]);
  if (d.normals().length) layout.push(['normal', 3]);
  if (d.colorComponents) layout.push(['color', d.colorComponents]);
  return layout;
}

function attributeView(d, name) {
  if (name === 'uv') return d.texcoords(0);
  if (name === 'uv1') return d.texcoords(1);
  if (name === 'normal') return d.normals();
  return d.colors();
}

// What changed since the last call (then d.clearChanges()): count render vertices and faces,
// positions / attributes of render vertices [vertexBegin, count), indices (and face materials)
// of faces [faceBegin, faces), rewritten faces below faceBegin as (face, a, b, c) with their
// materials, and with options.geomorph each new render vertex's start position (its position
// vertex's split parent; its own for old and base vertices and on full uploads) for
// [morphBegin, count). copy: typed-array copies (to post) instead of views into the heap.
// state ({shownVertices: 0} at first) remembers the position vertices already shown.
export function renderUpdate(d, state, options = {}) {
  const wedges = d.wedgeCount > 0;
  const count = wedges ? d.wedgeCount : d.vertexCount, faces = d.faceCount;
  const c = d.changes();
  const all = c.all;
  const vb = all ? 0 : Math.min(wedges ? c.wedgeBegin : c.vertexBegin, count);
  const fb = all ? 0 : Math.min(c.faceBegin, faces);
  const take = options.copy ? (a, b, e) => a.slice(b, e) : (a, b, e) => a.subarray(b, e);
  const u = {
    count, faces, all, vertexBegin: vb, faceBegin: fb,
    positions: take(wedges ? d.wedgePositions() : d.positions(), 3 * vb, 3 * count),
    indices: take(wedges ? d.wedgeIndices() : d.indices(), 3 * fb, 3 * faces),
    layout: attributeLayout(d), attributes: {}, faceMaterials: null,
    modified: null, modifiedMaterials: null, morph: null, morphBegin: count,
  };
  for (const [name, size] of u.layout) u.attributes[name] = take(attributeView(d, name), size * vb, size * count);
  const materials = d.materialCount > 1 ? d.faceMaterials() : null;  // one material: no groups
  if (materials && materials.length) u.faceMaterials = take(materials, fb, faces);
  if (!all && c.modifiedFaces.length) {
    const t = wedges ? d.wedgeIndices() : d.indices(), list = c.modifiedFaces;
    const m = new Uint32Array(4 * list.length);
    const mm = u.faceMaterials ? new Uint32Array(list.length) : null;
    for (let i = 0; i < list.length; ++i) {
      const f = list[i];
      m[4 * i] = f;
      m[4 * i + 1] = t[3 * f];
      m[4 * i + 2] = t[3 * f + 1];
      m[4 * i + 3] = t[3 * f + 2];
      if (mm) mm[i] = materials[f];
    }
    u.modified = m;
    u.modifiedMaterials = mm;
  }
  const nv = d.vertexCount;
  if (options.geomorph) {
    // New position vertices glide from their parent; so do the wedges on them.
    const from = all ? 0 : wedges ? vb : Math.max(vb, Math.min(state.shownVertices, nv));
    const p = d.positions(), parents = d.splitParents(), wv = wedges ? d.wedgeVertices() : null;
    const morph = new Float32Array(3 * (count - from));
    for (let r = from, i = 0; r < count; ++r, i += 3) {
      const v = wv ? wv[r] : r, parent = parents[v];
      const src = 3 * (all || parent === NONE || v < state.shownVertices ? v : parent);
      morph[i] = p[src];
      morph[i + 1] = p[src + 1];
      morph[i + 2] = p[src + 2];
    }
    u.morph = morph;
    u.morphBegin = from;
  }
  state.shownVertices = nv;
  return u;
}

// Copies of the whole render arrays (for snapshots): positions and indices of the render
// vertices, and the attributes by three.js name.
export function renderArrays(d) {
  const wedges = d.wedgeCount > 0, layout = attributeLayout(d), attributes = {};
  for (const [name] of layout) attributes[name] = attributeView(d, name).slice();
  return { positions: (wedges ? d.wedgePositions() : d.positions()).slice(),
    indices: (wedges ? d.wedgeIndices() : d.indices()).slice(), attributes, layout };
}

// The ArrayBuffers of an update made with copy: true, to transfer to another thread.
export function transferables(u) {
  const out = [u.positions.buffer, u.indices.buffer, ...Object.values(u.attributes).map((a) => a.buffer)];
  for (const a of [u.faceMaterials, u.modified, u.modifiedMaterials, u.morph]) if (a) out.push(a.buffer);
  return out;
}
