#include "simplify/apply.h"

#include <algorithm>

#include "simplify/levels.h"

namespace gtn {

std::vector<uint32_t> computeAncestors(const MergeTree& tree, uint64_t n) {
  const size_t np = tree.points();
  n = std::min<uint64_t>(n, tree.merges);
  std::vector<uint32_t> ancestor(np);
  // order[r - 1] = vertex of rank r.
  std::vector<uint32_t> order(tree.merges, MergeTree::kRoot);
  for (size_t v = 0; v < np; ++v) {
    ancestor[v] = static_cast<uint32_t>(v);
    if (tree.parent[v] != MergeTree::kRoot) order[tree.rank[v] - 1] = static_cast<uint32_t>(v);
  }
  // Descending rank visits every parent before its children; merges above n keep their own id.
  for (uint64_t r = n; r-- > 0;) {
    const uint32_t v = order[r];
    ancestor[v] = ancestor[tree.parent[v]];
  }
  return ancestor;
}

StatusOr<TetMesh> applyMerges(const TetMesh& mesh, const MergeTree& tree, uint64_t n, std::vector<uint32_t>* new_index,
                              const RuleGridTets* grid_tets) {
  if (tree.points() != mesh.numPoints())
    return invalidData("merge tree has " + std::to_string(tree.points()) + " vertices, the mesh " +
                       std::to_string(mesh.numPoints()));
  GTN_RETURN_IF_ERROR(tree.check("merge tree"));
  const std::vector<uint32_t> ancestor = computeAncestors(tree, n);
  const size_t np = mesh.numPoints();
  std::vector<uint32_t> index(np, MergeTree::kRoot);
  TetMesh out;
  out.coord_type = mesh.coord_type;
  out.metadata = mesh.metadata;
  uint32_t kept = 0;
  for (size_t v = 0; v < np; ++v) {
    if (ancestor[v] == v) index[v] = kept++;
  }
  out.coords.resize(3 * size_t{kept});
  for (const Field& f : mesh.point_fields) out.point_fields.emplace_back(f.name, f.components, f.type, kept);
  for (size_t v = 0; v < np; ++v) {
    if (index[v] == MergeTree::kRoot) continue;
    std::copy_n(mesh.point(v), 3, out.coords.data() + 3 * size_t{index[v]});
    for (size_t i = 0; i < mesh.point_fields.size(); ++i)
      out.point_fields[i].copyItem(mesh.point_fields[i], v, index[v]);
  }
  std::vector<size_t> kept_tets;
  if (grid_tets && ((!mesh.tets.empty() && mesh.tets.size() != grid_tets->size()) || grid_tets->points() != np))
    return usageError("applyMerges: a grid's tetrahedra given for a mesh of other points or tetrahedra");
  const size_t nt = grid_tets ? grid_tets->size() : mesh.numTets();
  for (size_t t = 0; t < nt; ++t) {
    Tet q = grid_tets ? (*grid_tets)[t] : mesh.tets[t];
    for (uint32_t& x : q) x = ancestor[x];
    if (q[0] == q[1] || q[0] == q[2] || q[0] == q[3] || q[1] == q[2] || q[1] == q[3] || q[2] == q[3]) continue;
    for (uint32_t& x : q) x = index[x];
    out.tets.push_back(q);
    kept_tets.push_back(t);
  }
  for (const Field& f : mesh.cell_fields) {
    Field g(f.name, f.components, f.type, kept_tets.size());
    for (size_t i = 0; i < kept_tets.size(); ++i) g.copyItem(f, kept_tets[i], i);
    out.cell_fields.push_back(std::move(g));
  }
  if (new_index) *new_index = std::move(index);
  return out;
}

MergeTree remainingTree(const MergeTree& tree, uint64_t n, const std::vector<uint32_t>& new_index) {
  n = std::min<uint64_t>(n, tree.merges);
  MergeTree out;
  size_t kept = 0;
  for (uint32_t x : new_index) kept += x != MergeTree::kRoot;
  out.makeRoots(kept);
  if (!tree.error.empty()) out.error.assign(kept, 0.0f);
  for (size_t v = 0; v < tree.points(); ++v) {
    const uint32_t i = new_index[v];
    if (i == MergeTree::kRoot || tree.parent[v] == MergeTree::kRoot) continue;
    // A survivor merges later than n, into a survivor (its parent merges later still, or never).
    out.parent[i] = new_index[tree.parent[v]];
    out.rank[i] = static_cast<uint32_t>(tree.rank[v] - n);
    out.removed[i] = tree.removed[v];
    out.boundary[i] = tree.boundary[v];
    if (!tree.error.empty()) out.error[i] = tree.error[v];
  }
  out.merges = tree.merges - n;
  out.batches = sliceBatches(tree.batches, n, tree.merges);
  out.batch_divisor = tree.batch_divisor;
  out.field = tree.field;
  out.w_density = tree.w_density;
  out.w_geometry = tree.w_geometry;
  computeErrorQuantiles(out);
  return out;
}

}  // namespace gtn

namespace gtn {

MergeTreeStats computeMergeTreeStats(const MergeTree& tree) {
  // Counted over the vertices tetrahedra use: the merges of the others, which come first, are left out.
  if (const uint64_t free = leadingFreeMerges(tree)) {
    std::vector<uint32_t> index(tree.points(), MergeTree::kRoot);
    uint32_t next = 0;
    for (size_t v = 0; v < tree.points(); ++v)
      if (tree.rank[v] == 0 || tree.rank[v] > free) index[v] = next++;
    return computeMergeTreeStats(remainingTree(tree, free, index));
  }
  MergeTreeStats s;
  const size_t np = tree.points();
  s.points = np;
  s.merges = tree.merges;
  s.roots = np - tree.merges;
  s.boundary_merges = tree.boundaryMergesUpTo(tree.merges);
  s.tets_removed = tree.tetsRemovedUpTo(tree.merges);
  std::vector<uint32_t> order(tree.merges, MergeTree::kRoot), depth(np, 0), children(np, 0);
  for (size_t v = 0; v < np; ++v) {
    if (tree.parent[v] == MergeTree::kRoot) continue;
    order[tree.rank[v] - 1] = static_cast<uint32_t>(v);
    ++children[tree.parent[v]];
  }
  double depth_sum = 0;
  for (uint64_t r = tree.merges; r-- > 0;) {
    const uint32_t v = order[r];
    depth[v] = depth[tree.parent[v]] + 1;
    s.depth_max = std::max<uint64_t>(s.depth_max, depth[v]);
    depth_sum += depth[v];
  }
  s.depth_mean = np ? depth_sum / double(np) : 0;
  uint64_t parents = 0, child_sum = 0;
  for (uint32_t c : children) {
    if (!c) continue;
    ++parents;
    child_sum += c;
    s.fanout_max = std::max<uint64_t>(s.fanout_max, c);
  }
  s.fanout_mean = parents ? double(child_sum) / double(parents) : 0;
  return s;
}

}  // namespace gtn
