#include "codec/merge_tree_coder.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

#include "codec/range_coder.h"

namespace gtn {

const double kMergeErrorQuantiles[9] = {0.0, 0.01, 0.1, 0.25, 0.5, 0.75, 0.9, 0.99, 1.0};

uint64_t MergeTree::boundaryMergesUpTo(uint64_t n) const {
  uint64_t count = 0;
  for (size_t v = 0; v < parent.size(); ++v) {
    if (parent[v] != kRoot && rank[v] <= n && !boundary.empty() && boundary[v]) ++count;
  }
  return count;
}

uint64_t MergeTree::tetsRemovedUpTo(uint64_t n) const {
  uint64_t count = 0;
  for (size_t v = 0; v < parent.size(); ++v) {
    if (parent[v] != kRoot && rank[v] <= n && !removed.empty()) count += removed[v];
  }
  return count;
}

Status MergeTree::check(const std::string& what) const {
  const size_t n = parent.size();
  if (rank.size() != n || removed.size() != n || boundary.size() != n)
    return invalidData(what + ": merge tree arrays differ in size");
  if (merges > n) return invalidData(what + ": merge tree has more merges than vertices");
  std::vector<uint8_t> seen(merges + 1, 0);
  uint64_t merged = 0;
  for (size_t v = 0; v < n; ++v) {
    if (parent[v] == kRoot) {
      if (rank[v] != 0) return invalidData(what + ": root vertex " + std::to_string(v) + " has a rank");
      continue;
    }
    ++merged;
    if (parent[v] >= n || parent[v] == v)
      return invalidData(what + ": vertex " + std::to_string(v) + " has an invalid parent");
    if (rank[v] == 0 || rank[v] > merges || seen[rank[v]])
      return invalidData(what + ": vertex " + std::to_string(v) + " has an invalid or repeated rank");
    seen[rank[v]] = 1;
    const uint32_t p = parent[v];
    if (parent[p] != kRoot && rank[p] <= rank[v])
      return invalidData(what + ": vertex " + std::to_string(v) + " merges into a vertex merged earlier");
  }
  if (merged != merges) return invalidData(what + ": merge count disagrees with the tree");
  return Status::ok();
}

void computeErrorQuantiles(MergeTree& tree) {
  tree.error_quantiles.clear();
  if (tree.error.size() != tree.parent.size() || tree.merges == 0) return;
  std::vector<float> e;
  e.reserve(tree.merges);
  for (size_t v = 0; v < tree.parent.size(); ++v) {
    if (tree.parent[v] != MergeTree::kRoot) e.push_back(tree.error[v]);
  }
  if (e.empty()) return;
  std::sort(e.begin(), e.end());
  for (double q : kMergeErrorQuantiles) {
    const size_t i = std::min(e.size() - 1, static_cast<size_t>(std::llround(q * double(e.size() - 1))));
    tree.error_quantiles.push_back(e[i]);
  }
}

namespace {

int bitLength(uint64_t x) { return x == 0 ? 0 : 64 - __builtin_clzll(x); }

// Adaptive models of the body (one instance per encoder or decoder).
struct Models {
  BitModel is_root, boundary;
  BitTree<4> choice;     // which recent parent delta predicts this one (0 = none)
  BitModel sign[2];      // per context (choice == 0 or not)
  BitTree<6> len[2];
  BitTree<4> removed[2];
};

// x in [0, total), 1 <= total, as a truncated binary code of direct bits.
template <class C>
uint32_t codeUniform(C& c, uint32_t x, uint32_t total) {
  if (total <= 1) return 0;
  const int b = bitLength(total - 1);
  const uint32_t u = static_cast<uint32_t>((uint64_t{1} << b) - total);  // codes one bit shorter
  uint32_t y = c.direct(x < u ? x : (x + u) >> 1, b - 1);
  if (y < u) return y;
  y = (y << 1) | c.direct((x + u) & 1, 1);
  return y - u;
}

// The parent deltas (parent id - child id) of the last merged vertices, most recent first: nearby
// vertices in decoding order tend to merge in the same direction.
struct DeltaHistory {
  static constexpr int kSize = 8;
  int64_t d[kSize] = {};
  int count = 0;
  void push(int64_t delta) {
    for (int k = kSize - 1; k > 0; --k) d[k] = d[k - 1];
    d[0] = delta;
    count = std::min(count + 1, kSize);
  }
};

// The per-vertex body of the payload, shared by the encoder (values in, returned unchanged) and the
// decoder (values out).
struct VertexCode {
  bool root;
  uint32_t choice, sign, len, low_bits, rank_index, boundary, removed;
};

template <class C>
void codeVertex(C& c, Models& m, VertexCode& v, uint32_t remaining) {
  v.root = c.bit(m.is_root, v.root ? 1 : 0) != 0;
  if (v.root) return;
  v.choice = m.choice.code(c, v.choice);
  const int ctx = v.choice ? 1 : 0;
  v.len = m.len[ctx].code(c, v.len);
  if (v.len > 33) return;  // only a corrupt stream gets here; the decoder rejects it
  if (v.len > 0) {
    v.sign = c.bit(m.sign[ctx], v.sign);
    v.low_bits = c.direct(v.low_bits, static_cast<int>(v.len) - 1);
  }
  v.rank_index = codeUniform(c, v.rank_index, remaining);
  v.boundary = c.bit(m.boundary, v.boundary);
  const uint32_t k = m.removed[v.boundary].code(c, std::min<uint32_t>(v.removed, 15));
  v.removed = k == 15 ? c.direct(v.removed, 32) : k;
}

// The ranks 1..M still free: one bit per rank, and a Fenwick tree over the free counts of 64-rank
// blocks, small enough to stay in cache while the Lehmer code is decoded.
class FreeRanks {
 public:
  explicit FreeRanks(uint32_t m) : bits_((size_t{m} + 63) / 64, ~uint64_t{0}), blocks_(bits_.size()) {
    if (m % 64) bits_.back() = (uint64_t{1} << (m % 64)) - 1;
    tree_.assign(blocks_ + 1, 0);
    for (size_t b = 1; b <= blocks_; ++b) {
      tree_[b] += static_cast<uint32_t>(std::popcount(bits_[b - 1]));
      const size_t j = b + (b & (0 - b));
      if (j <= blocks_) tree_[j] += tree_[b];
    }
    top_ = 1;
    while (top_ * 2 <= blocks_) top_ *= 2;
  }
  // Free ranks smaller than r.
  uint32_t countBelow(uint32_t r) const {
    const uint32_t i = r - 1;
    uint32_t s = 0;
    for (size_t b = i >> 6; b > 0; b -= b & (0 - b)) s += tree_[b];
    return s + static_cast<uint32_t>(std::popcount(bits_[i >> 6] & ((uint64_t{1} << (i & 63)) - 1)));
  }
  void take(uint32_t r) {
    const uint32_t i = r - 1;
    bits_[i >> 6] &= ~(uint64_t{1} << (i & 63));
    for (size_t b = (i >> 6) + 1; b <= blocks_; b += b & (0 - b)) tree_[b] -= 1;
  }
  // The (k+1)-th smallest free rank (k < free count).
  uint32_t kth(uint32_t k) const {
    size_t pos = 0;
    uint32_t rem = k;  // free ranks still to skip
    for (size_t step = top_; step > 0; step >>= 1) {
      if (pos + step <= blocks_ && tree_[pos + step] <= rem) {
        pos += step;
        rem -= tree_[pos];
      }
    }
    // Block `pos` holds it: skip `rem` set bits.
    uint64_t w = bits_[pos];
    for (uint32_t j = 0; j < rem; ++j) w &= w - 1;
    return static_cast<uint32_t>(pos * 64 + std::countr_zero(w)) + 1;
  }

 private:
  std::vector<uint64_t> bits_;
  size_t blocks_;
  std::vector<uint32_t> tree_;
  size_t top_ = 1;
};

void putVarint(std::vector<uint8_t>& out, uint64_t v) {
  while (v >= 0x80) {
    out.push_back(static_cast<uint8_t>(v | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<uint8_t>(v));
}

void putF64(std::vector<uint8_t>& out, double d) {
  uint8_t b[8];
  std::memcpy(b, &d, 8);  // the project assumes a little-endian host
  out.insert(out.end(), b, b + 8);
}

class Reader {
 public:
  Reader(std::span<const uint8_t> in, const std::string& what) : in_(in), what_(what) {}
  Status varint(uint64_t* v, const char* field) {
    uint64_t result = 0;
    for (int shift = 0; shift < 70; shift += 7) {
      if (pos_ >= in_.size()) return error(field, "truncated");
      const uint8_t b = in_[pos_++];
      if (shift == 63 && (b & 0x7E)) return error(field, "varint overflows 64 bits");
      result |= uint64_t{b & 0x7Fu} << shift;
      if (!(b & 0x80)) {
        *v = result;
        return Status::ok();
      }
    }
    return error(field, "varint longer than 10 bytes");
  }
  Status u8(uint8_t* v, const char* field) {
    if (pos_ >= in_.size()) return error(field, "truncated");
    *v = in_[pos_++];
    return Status::ok();
  }
  Status f64(double* v, const char* field) {
    if (in_.size() - pos_ < 8) return error(field, "truncated");
    std::memcpy(v, in_.data() + pos_, 8);
    pos_ += 8;
    return Status::ok();
  }
  Status bytes(uint64_t n, std::span<const uint8_t>* out, const char* field) {
    if (n > in_.size() - pos_) return error(field, "length exceeds the payload");
    *out = in_.subspan(pos_, n);
    pos_ += n;
    return Status::ok();
  }
  Status error(const char* field, const std::string& why) const {
    return invalidData(what_ + ": merge tree payload, byte " + std::to_string(pos_) + " (" + field + "): " + why);
  }
  size_t pos() const { return pos_; }
  size_t size() const { return in_.size(); }

 private:
  std::span<const uint8_t> in_;
  size_t pos_ = 0;
  const std::string& what_;
};

constexpr uint8_t kVersion = 1;

}  // namespace

StatusOr<std::vector<uint8_t>> encodeMergeTree(const MergeTree& tree, const std::vector<uint32_t>& vertex_order) {
  GTN_RETURN_IF_ERROR(tree.check("merge tree"));
  const size_t n = tree.points();
  if (vertex_order.size() != n) return invalidData("merge tree: vertex order has the wrong size");
  if (n > 0xFFFFFFF0u) return unsupported("merge tree: more than 2^32 - 16 vertices");
  // inverse[id] = source vertex with decoding id `id`.
  std::vector<uint32_t> inverse(n, MergeTree::kRoot);
  for (size_t v = 0; v < n; ++v) {
    const uint32_t id = vertex_order[v];
    if (id >= n || inverse[id] != MergeTree::kRoot) return invalidData("merge tree: vertex order is not a permutation");
    inverse[id] = static_cast<uint32_t>(v);
  }
  std::vector<uint8_t> out;
  out.push_back(kVersion);
  putVarint(out, n);
  putVarint(out, tree.merges);
  putVarint(out, tree.boundaryMergesUpTo(tree.merges));
  putVarint(out, tree.tetsRemovedUpTo(tree.merges));
  putF64(out, tree.w_density);
  putF64(out, tree.w_geometry);
  putVarint(out, tree.field.size());
  out.insert(out.end(), tree.field.begin(), tree.field.end());
  const size_t q = tree.error_quantiles.size() == 9 ? 9 : 0;
  out.push_back(static_cast<uint8_t>(q));
  for (size_t i = 0; i < q; ++i) putF64(out, tree.error_quantiles[i]);

  std::vector<uint8_t> body;
  EntropyCoder<true> rc(&body);
  Models m;
  FreeRanks free_ranks(static_cast<uint32_t>(tree.merges));
  uint32_t remaining = static_cast<uint32_t>(tree.merges);
  DeltaHistory history;
  for (uint32_t id = 0; id < n; ++id) {
    const uint32_t v = inverse[id];
    VertexCode code{};
    code.root = tree.parent[v] == MergeTree::kRoot;
    if (!code.root) {
      const int64_t delta = int64_t{vertex_order[tree.parent[v]]} - int64_t{id};
      int64_t residual = delta;
      code.choice = 0;
      for (int k = 0; k < history.count; ++k) {
        const int64_t r = delta - history.d[k];
        if (std::llabs(r) < std::llabs(residual)) {
          residual = r;
          code.choice = static_cast<uint32_t>(k + 1);
        }
      }
      history.push(delta);
      const uint64_t mag = static_cast<uint64_t>(std::llabs(residual));
      code.len = static_cast<uint32_t>(bitLength(mag));
      code.sign = residual < 0 ? 1 : 0;
      code.low_bits = code.len > 1 ? static_cast<uint32_t>(mag & ((uint64_t{1} << (code.len - 1)) - 1)) : 0;
      code.rank_index = free_ranks.countBelow(tree.rank[v]);
      code.boundary = tree.boundary[v] ? 1 : 0;
      code.removed = tree.removed[v];
    }
    codeVertex(rc, m, code, remaining);
    if (!code.root) {
      free_ranks.take(tree.rank[v]);
      --remaining;
    }
  }
  rc.finish();
  putVarint(out, body.size());
  out.insert(out.end(), body.begin(), body.end());
  return out;
}

StatusOr<MergeTree> decodeMergeTree(std::span<const uint8_t> payload, uint64_t expected_points,
                                    const std::string& what) {
  Reader r(payload, what);
  uint8_t version = 0;
  GTN_RETURN_IF_ERROR(r.u8(&version, "version"));
  if (version != kVersion) return r.error("version", "unsupported version " + std::to_string(version));
  uint64_t points = 0, merges = 0, boundary_merges = 0, tets_removed = 0;
  GTN_RETURN_IF_ERROR(r.varint(&points, "points"));
  if (points != expected_points)
    return r.error("points", std::to_string(points) + " vertices, the level has " + std::to_string(expected_points));
  if (points > 0xFFFFFFF0u) return r.error("points", "more than 2^32 - 16 vertices");
  GTN_RETURN_IF_ERROR(r.varint(&merges, "merges"));
  if (merges > points) return r.error("merges", "more merges than vertices");
  GTN_RETURN_IF_ERROR(r.varint(&boundary_merges, "boundary_merges"));
  if (boundary_merges > merges) return r.error("boundary_merges", "more boundary merges than merges");
  GTN_RETURN_IF_ERROR(r.varint(&tets_removed, "tets_removed"));
  MergeTree tree;
  GTN_RETURN_IF_ERROR(r.f64(&tree.w_density, "w_density"));
  GTN_RETURN_IF_ERROR(r.f64(&tree.w_geometry, "w_geometry"));
  uint64_t name_len = 0;
  GTN_RETURN_IF_ERROR(r.varint(&name_len, "field name length"));
  std::span<const uint8_t> name;
  GTN_RETURN_IF_ERROR(r.bytes(name_len, &name, "field name"));
  tree.field.assign(name.begin(), name.end());
  uint8_t q = 0;
  GTN_RETURN_IF_ERROR(r.u8(&q, "quantile count"));
  if (q != 0 && q != 9) return r.error("quantile count", "must be 0 or 9");
  for (int i = 0; i < q; ++i) {
    double d = 0;
    GTN_RETURN_IF_ERROR(r.f64(&d, "quantile"));
    tree.error_quantiles.push_back(d);
  }
  uint64_t body_len = 0;
  GTN_RETURN_IF_ERROR(r.varint(&body_len, "body length"));
  std::span<const uint8_t> body;
  GTN_RETURN_IF_ERROR(r.bytes(body_len, &body, "body"));
  if (r.pos() != r.size()) return r.error("end", "trailing bytes after the body");

  const size_t n = points;
  tree.merges = merges;
  tree.parent.assign(n, MergeTree::kRoot);
  tree.rank.assign(n, 0);
  tree.removed.assign(n, 0);
  tree.boundary.assign(n, 0);
  EntropyCoder<false> rc(body);
  Models m;
  FreeRanks free_ranks(static_cast<uint32_t>(merges));
  uint32_t remaining = static_cast<uint32_t>(merges);
  uint64_t got_boundary = 0, got_removed = 0;
  DeltaHistory history;
  auto bodyError = [&](uint32_t id, const std::string& why) {
    return invalidData(what + ": merge tree payload body, vertex " + std::to_string(id) + ": " + why);
  };
  for (uint32_t id = 0; id < n; ++id) {
    if (!rc.ok()) return bodyError(id, "body truncated or corrupt");
    VertexCode code{};
    codeVertex(rc, m, code, remaining);
    if (code.root) continue;
    if (remaining == 0) return bodyError(id, "more merged vertices than merges");
    if (code.choice > static_cast<uint32_t>(history.count)) return bodyError(id, "parent predictor out of range");
    if (code.len > 33) return bodyError(id, "parent delta too long");
    const int64_t mag = code.len == 0 ? 0 : static_cast<int64_t>((uint64_t{1} << (code.len - 1)) | code.low_bits);
    const int64_t delta = (code.choice ? history.d[code.choice - 1] : 0) + (code.sign ? -mag : mag);
    const int64_t pid64 = int64_t{id} + delta;
    if (delta == 0 || pid64 < 0 || pid64 >= static_cast<int64_t>(n)) return bodyError(id, "parent id out of range");
    history.push(delta);
    const uint64_t pid = static_cast<uint64_t>(pid64);
    if (code.rank_index >= remaining) return bodyError(id, "rank out of range");
    const uint32_t rank = free_ranks.kth(code.rank_index);
    free_ranks.take(rank);
    --remaining;
    tree.parent[id] = static_cast<uint32_t>(pid);
    tree.rank[id] = rank;
    tree.boundary[id] = static_cast<uint8_t>(code.boundary);
    tree.removed[id] = code.removed;
    got_boundary += code.boundary;
    got_removed += code.removed;
  }
  if (!rc.finishedCleanly()) return invalidData(what + ": merge tree payload body truncated, corrupt or followed by trailing bytes");
  if (remaining != 0) return invalidData(what + ": merge tree payload has fewer merged vertices than merges");
  if (got_boundary != boundary_merges || got_removed != tets_removed)
    return invalidData(what + ": merge tree payload counts disagree with its header");
  for (size_t v = 0; v < n; ++v) {
    const uint32_t p = tree.parent[v];
    if (p != MergeTree::kRoot && tree.parent[p] != MergeTree::kRoot && tree.rank[p] <= tree.rank[v])
      return invalidData(what + ": merge tree payload: vertex " + std::to_string(v) +
                         " merges into a vertex merged earlier");
  }
  return tree;
}

}  // namespace gtn
