#include "render/stream_renderer.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "mesh/faces.h"
#include "mesh/index.h"
#include "render/flat_hash.h"
#include "render/traversal.h"

namespace gtn {

using render_internal::advanceCursor;
using render_internal::CursorEnd;
using render_internal::Link;
using render_internal::SegmentCursors;

namespace {

constexpr uint32_t kOpenFace = kNoIndex;         // neighbour not arrived (or never will)
constexpr uint32_t kReleasedFace = 0xFFFFFFFEu;  // neighbour arrived and was released
// Tetrahedra are processed in batches of this size range: large enough to feed the threads, small
// relative to the mesh so that holding a batch does not dominate the memory.
constexpr size_t kMinBatch = 256, kMaxBatch = 2048;

struct FaceKey {
  uint32_t v[3];
  bool operator==(const FaceKey& o) const { return v[0] == o.v[0] && v[1] == o.v[1] && v[2] == o.v[2]; }
};
struct FaceKeyHash {
  size_t operator()(const FaceKey& k) const {
    uint64_t h = k.v[0] * 0x9E3779B97F4A7C15ull;
    h ^= (h >> 29) + k.v[1] * 0xC2B2AE3D27D4EB4Full;
    h ^= (h >> 31) + k.v[2] * 0x165667B19E3779F9ull;
    return static_cast<size_t>(h ^ (h >> 32));
  }
};
FaceKey makeKey(uint32_t a, uint32_t b, uint32_t c) {
  if (a > b) std::swap(a, b);
  if (b > c) std::swap(b, c);
  if (a > b) std::swap(a, b);
  return {{a, b, c}};
}

struct IdHash {
  size_t operator()(uint32_t id) const { return static_cast<size_t>((id * 0x9E3779B97F4A7C15ull) >> 20); }
};

// A face of a held tetrahedron in one word: (slot << 2) | local face.
uint32_t heldFace(uint32_t slot, int face) { return slot << 2 | static_cast<uint32_t>(face); }

// A face where cursors wait: the one held tetrahedron that has it (if any is held) and the cursors
// (2 * segment + 0 front / 1 back) waiting for the tetrahedron on its other side, as a list linked
// through State::cursor_word. The tetrahedron's slot and local face share one word (20-byte map
// entries).
struct FaceEntry {
  uint32_t held = kNoIndex;     // heldFace, or kNoIndex
  uint32_t waiters = kNoIndex;  // the first waiting cursor, or kNoIndex
  bool hasTet() const { return held != kNoIndex; }
  uint32_t tet() const { return held >> 2; }
  int face() const { return static_cast<int>(held & 3); }
  void setTet(uint32_t slot, int face) { held = heldFace(slot, face); }
};
// Held tetrahedra have slots below this, so that (slot << 2) | face fits FaceEntry::held.
constexpr uint32_t kMaxHeldSlots = 0x3FFFFFFFu;

// A vertex as the renderer keeps it, shared by the live-vertex map and by every arrived or held
// tetrahedron that has it as a corner: held tetrahedra point to their corners instead of copying
// them (a held tetrahedron took 192 bytes, now 64, and neighbours share corners). One cache line.
//
// `refs` counts 1 while the vertex is live plus one per held tetrahedron. The two threads never
// change it at once: the rendering thread counts the held tetrahedra while it renders a batch, and
// the decoder's thread drops the live count between batches (State::settle), once the batch that was
// filling when the vertex retired has been rendered (it is the last that can have the vertex as a
// corner). A vertex whose count reaches zero is freed between batches too.
struct alignas(64) PooledVertex : CornerRecord {  // q: orthographic, set once the frame is known
  uint32_t id;
  int32_t refs;
};

// The vertices, in chunks of fixed size (addresses stay put as the pool grows), with a free list
// linked through the freed records themselves (a list beside them took up to 200 KB at once on
// combustion). Used by the decoder's thread only.
class VertexPool {
 public:
  PooledVertex* allocate() {
    if (free_) {
      PooledVertex* v = free_;
      std::memcpy(&free_, v->p, sizeof free_);
      return v;
    }
    if (chunks_.empty() || used_ == kChunk) {
      chunks_.push_back(std::unique_ptr<PooledVertex[]>(new PooledVertex[kChunk]));
      used_ = 0;
    }
    return &chunks_.back()[used_++];
  }
  // A freed record keeps the one freed before it where its position was.
  void free(PooledVertex* v) {
    std::memcpy(v->p, &free_, sizeof free_);
    free_ = v;
  }

 private:
  static constexpr size_t kChunk = 1024;  // 64 KiB
  std::vector<std::unique_ptr<PooledVertex[]>> chunks_;
  size_t used_ = 0;               // entries of the last chunk handed out
  PooledVertex* free_ = nullptr;  // the last freed record
};

// One cache line each.
struct alignas(64) HeldTet {
  CornerRecord* corner[4];  // PooledVertex; corner[0] is null while the slot is free
  uint32_t nbr[4];          // the neighbour's heldFace, or kOpenFace / kReleasedFace
  uint8_t order[4][3];      // TetGeom::order
  std::atomic<int32_t> pending{0};
  bool alive() const { return corner[0] != nullptr; }
  // While the slot is free: the slot freed before it (SlotPool's list), where the orders were.
  uint32_t nextFree() const {
    uint32_t n;
    std::memcpy(&n, order, sizeof n);
    return n;
  }
  void setNextFree(uint32_t n) { std::memcpy(order, &n, sizeof n); }
  PooledVertex* vertex(int i) const { return static_cast<PooledVertex*>(corner[i]); }
  FaceKey key(int k) const {
    return makeKey(vertex(kTetFace[k][0])->id, vertex(kTetFace[k][1])->id, vertex(kTetFace[k][2])->id);
  }
};

// Entries in chunks of fixed size, with a free list linked through the freed entries (T::nextFree,
// T::setNextFree): addresses stay put as the pool grows (HeldTet holds an atomic), and an index
// finds its chunk by a shift. (std::deque fits two HeldTets in a block: a quarter of each block
// wasted, and an index costs a division.)
template <class T, uint32_t kShift>
class SlotPool {
 public:
  T& operator[](uint32_t i) { return chunks_[i >> kShift][i & kMask]; }
  uint32_t size() const { return size_; }  // indices handed out, freed ones included
  // A freed index, else a new, default-constructed entry at the end.
  uint32_t allocate() {
    if (free_ != kNoIndex) {
      const uint32_t i = free_;
      free_ = (*this)[i].nextFree();
      return i;
    }
    if ((size_ >> kShift) == chunks_.size()) chunks_.push_back(std::make_unique<T[]>(kChunk));
    return size_++;
  }
  void free(uint32_t i) {
    (*this)[i].setNextFree(free_);
    free_ = i;
  }

 private:
  static constexpr uint32_t kChunk = 1u << kShift, kMask = kChunk - 1;
  std::vector<std::unique_ptr<T[]>> chunks_;
  uint32_t free_ = kNoIndex;  // the last freed index
  uint32_t size_ = 0;
};

// A colour as segments keep it between batches: float, which rounds it by at most 2e-5 of a grey
// level (the compositing itself stays double, as the generic renderer's).
struct StoredRgba {
  float r = 0, g = 0, b = 0, a = 0;
  StoredRgba() = default;
  explicit StoredRgba(const Rgba& c)
      : r(static_cast<float>(c.r)),
        g(static_cast<float>(c.g)),
        b(static_cast<float>(c.b)),
        a(static_cast<float>(c.a)) {}
  Rgba get() const { return {r, g, b, a}; }
};

// A segment as the streaming renderer keeps it (48 bytes, not SegmentState's 88). The back cursor's
// colour is kept apart (State::backs) from the batch in which it first stops being blank until the
// segment is done, when it is composited into `front` (over(over(f, b), 0) is over(f, b), bit for
// bit): when the most tetrahedra are held, early in the level, most back cursors have composited
// nothing but transparent samples.
struct StreamSegment : SegmentCursors {
  StoredRgba front;
  uint32_t back = kNoIndex;  // index into State::backs; none while the back colour is blank (zero)
  uint32_t pixel = 0;        // whose ray
};
static_assert(sizeof(StreamSegment) == 48);

// Whether c is exactly the zero colour (+0, so that leaving it out changes no bit).
bool isBlank(const Rgba& c) {
  const Rgba zero;
  return std::memcmp(&c, &zero, sizeof(Rgba)) == 0;
}

// The back colours that are not blank, in chunks. Entries are taken and given back by the tasks that
// advance cursors, each thread keeping the entries it gives back for its next ones (no lock); only
// growing takes a lock. The chunk directory is reserved for one entry per segment, so that it never
// moves while other tasks read entries.
class BackColours {
 public:
  void reserve(size_t segments) { chunks_.reserve(segments / kChunk + 1); }
  StoredRgba& operator[](uint32_t i) { return chunks_[i >> kShift][i & kMask]; }
  uint32_t allocate(const StoredRgba& c) {
    std::vector<uint32_t>& mine = free_.local();
    uint32_t i;
    if (!mine.empty()) {
      i = mine.back();
      mine.pop_back();
    } else {
      std::lock_guard<std::mutex> lock(grow_);
      if ((size_ >> kShift) == chunks_.size()) chunks_.push_back(std::make_unique<StoredRgba[]>(kChunk));
      i = size_++;
    }
    (*this)[i] = c;
    return i;
  }
  void free(uint32_t i) { free_.local().push_back(i); }

 private:
  static constexpr uint32_t kShift = 10, kChunk = 1u << kShift, kMask = kChunk - 1;
  std::vector<std::unique_ptr<StoredRgba[]>> chunks_;
  tbb::enumerable_thread_specific<std::vector<uint32_t>> free_;
  uint32_t size_ = 0;
  std::mutex grow_;
};

constexpr uint8_t kNoOrder = 0xFF;  // ArrivedTet::order[0][0] before the orders are computed

struct ArrivedTet {
  CornerRecord* corner[4];  // PooledVertex
  uint8_t order[4][3];      // TetGeom::order, computed when the batch is rendered if needed
  int32_t rays = 0;
  // Whether some pixel's centre may lie in its projection (pixelFootprint, with its margin): when
  // not, no ray crosses its faces and no cursor can wait at them.
  bool visible = false;
  PooledVertex* vertex(int i) const { return static_cast<PooledVertex*>(corner[i]); }
  void computeOrder() {
    if (order[0][0] != kNoOrder) return;
    const double* p[4] = {corner[0]->p, corner[1]->p, corner[2]->p, corner[3]->p};
    faceOrders(p, order);
  }
};

}  // namespace

struct StreamRenderer::State {
  enum class Phase { kIdle, kBoundary, kTets, kDone };
  Phase phase = Phase::kIdle;
  LevelHeader header;
  ScalarReader reader;
  VertexPool pool;
  FlatHashMap<uint32_t, PooledVertex*, IdHash> ids;  // the live vertices (decoder's thread)
  std::vector<PooledVertex*> retired;                // retired while `batch` was filled
  std::vector<PooledVertex*> retired_flushing;       // retired while `flushing` was filled
  std::vector<PooledVertex*> unheld;                 // counts that reached zero in the rendering thread, to free
  std::vector<std::array<uint32_t, 3>> boundary;
  // The first segment of every kPixelBlock-th pixel. Segments are stored in pixel order and know
  // their pixel, so any pixel's are found by a short walk from its block's first: an eighth of
  // castBoundary's offset per pixel (256 KB at 256x256). The walks stop at a last, empty segment of
  // no pixel (kNoIndex), which they need not test for.
  static constexpr uint32_t kPixelBlock = 8;
  std::vector<uint32_t> block_start;
  // Each pixel's number of segments, 255 for 255 or more: counting a tetrahedron's rays reads these
  // bytes, not the segments, for the pixels it covers (in a valid mesh a pixel with one segment whose
  // centre lies clearly inside the tetrahedron's projection always needs it).
  std::vector<uint8_t> pixel_segments;
  // The first segment of pixel p or of a later pixel.
  uint32_t firstSegmentFrom(uint32_t p) const {
    uint32_t s = block_start[p / kPixelBlock];
    while (segs[s].pixel < p) ++s;
    return s;
  }
  // The end of pixel p's segments, which begin at s (firstSegmentFrom for p, or the end of the
  // pixel before p).
  uint32_t pixelSegmentsEnd(uint32_t p, uint32_t s) const {
    while (segs[s].pixel == p) ++s;
    return s;
  }
  // Rays are not stored per pixel (that would be the largest structure at 256x256): prepareRay is
  // cheap and deterministic, so recomputing a pixel's ray gives the very same crossings.
  PreparedRay pixelRay(size_t p, const Camera& camera) const {
    const Ray r = camera.ray(static_cast<int>(p % camera.width()), static_cast<int>(p / camera.width()));
    if (!shared_frame) return prepareRay(r);
    // Orthographic rays share their direction, hence prepareRay's frame: only the origin is sheared.
    PreparedRay ray;
    ray.ray = r;
    ray.frame = frame;
    shearPoint(frame, r.o, ray.origin);
    return ray;
  }
  bool shared_frame = false;  // orthographic: every ray has `frame`
  ShearFrame frame;
  std::vector<StreamSegment> segs;
  BackColours backs;
  FlatHashMap<FaceKey, FaceEntry, FaceKeyHash> faces;
  // One word per cursor, allocated once at endBoundary. While the cursor waits at a face, the next
  // cursor waiting there: the waiter lists of `faces` (a cursor waits at one face at a time). From
  // the batch that takes it off its list until it waits again, the heldFace it enters or, once it
  // has stopped, the one where it is to wait; so the batch's lists hold bare cursors.
  std::vector<uint32_t> cursor_word;
  void addWaiter(FaceEntry& e, uint32_t cursor) {
    cursor_word[cursor] = e.waiters;
    e.waiters = cursor;
  }
  // Calls f(cursor) for each waiter of e and empties its list (f may set the cursor's word).
  template <class F>
  void takeWaiters(FaceEntry& e, F&& f) {
    for (uint32_t c = e.waiters; c != kNoIndex;) {
      const uint32_t next = cursor_word[c];
      f(c);
      c = next;
    }
    e.waiters = kNoIndex;
  }
  SlotPool<HeldTet, 9> tets;
  uint64_t held = 0;
  std::vector<ArrivedTet> batch;     // filled by the decoder
  std::vector<ArrivedTet> flushing;  // rendered (flushBatch) meanwhile, on another thread
  tbb::task_group flush_task;
  bool flush_running = false;
  size_t batch_size = kMinBatch;

  ~State() { waitFlush(); }
  void waitFlush() {
    if (flush_running) flush_task.wait();
    flush_running = false;
  }
  Status flush_status;  // what the last flushBatch returned (it runs on another thread)
  // Between batches, with no flush running: the vertices retired while the batch just rendered was
  // filled stop counting as live, and those that nothing holds are freed.
  void settle() {
    flushing.clear();
    for (PooledVertex* v : retired_flushing)
      if (--v->refs == 0) pool.free(v);
    retired_flushing.swap(retired);
    retired.clear();
    for (PooledVertex* v : unheld) pool.free(v);
    unheld.clear();
  }
  std::atomic<uint64_t> lost{0};
  // flushBatch's lists, kept from one batch to the next (cleared, not freed).
  // The segments with a cursor that enters a tetrahedron of the batch, each once, and per segment
  // which of its cursors do (bit 0 the front, bit 1 the back; zero outside flushBatch's steps 2-3).
  std::vector<uint32_t> trigger_segs;
  std::vector<uint8_t> triggered;
  // Per segment, which cursors stopped at the boundary (bit 0 the front, bit 1 the back; the back of
  // a segment without an exit triangle from the start): a segment left undone otherwise lost its ray.
  std::vector<uint8_t> at_boundary;
  std::vector<uint32_t> unpaired;  // castBoundary's: pixels whose boundary crossings do not pair
  void trigger(uint32_t cursor) {
    uint8_t& bits = triggered[cursor / 2];
    if (bits == 0) trigger_segs.push_back(cursor / 2);
    bits |= static_cast<uint8_t>(1u << (cursor % 2));
  }
  std::vector<uint32_t> arrived_slots;
  tbb::enumerable_thread_specific<std::vector<uint32_t>> zeroed;  // pending fell to zero
  tbb::enumerable_thread_specific<std::vector<uint32_t>> waits;   // cursors to wait at open faces

  void release(uint32_t slot);
};

namespace {
// The held tetrahedra as advanceCursor sees them.
struct HeldMesh {
  StreamRenderer::State& st;
  tbb::enumerable_thread_specific<std::vector<uint32_t>>& zeroed;

  // Orthographic views use the corners' sheared positions, as shearTetGeom would.
  TetCorners geom(uint32_t t) const {
    const HeldTet& h = st.tets[t];
    return {h.corner, h.order, st.shared_frame};
  }
  Link next(uint32_t t, int face, uint32_t* nt, int* nf) {
    const uint32_t n = st.tets[t].nbr[face];
    if (n == kOpenFace) return Link::kOpen;
    if (n == kReleasedFace) return Link::kReleased;
    *nt = n >> 2;
    *nf = static_cast<int>(n & 3);
    return Link::kLinked;
  }
  void visited(uint32_t t) {
    if (st.tets[t].pending.fetch_sub(1, std::memory_order_relaxed) <= 1) zeroed.local().push_back(t);
  }
};
}  // namespace

namespace {
// castBoundary's segments, each made a segment state whose cursors wait at its boundary triangles.
class SegmentBuilder : public SegmentSink {
 public:
  explicit SegmentBuilder(StreamRenderer::State& st) : st_(st) {}
  void begin(size_t segments) override {
    st_.segs.resize(segments + 1);
    st_.segs.back().pixel = kNoIndex;  // State::block_start's walks end there
    st_.backs.reserve(segments);
    st_.cursor_word.assign(2 * segments, kNoIndex);
    st_.triggered.assign(segments, 0);
    st_.at_boundary.assign(segments, 0);
  }
  void segment(const RaySegment& rs) override {
    const size_t i = next_++;
    StreamSegment& seg = st_.segs[i];
    seg.tf = rs.t_near, seg.sf = static_cast<float>(rs.s_near), seg.tb = rs.t_far,
    seg.sb = static_cast<float>(rs.s_far);
    seg.pixel = rs.pixel;
    if (seg.done()) return;
    const auto& in = st_.boundary[rs.entry_tri];
    st_.addWaiter(*st_.faces.tryEmplace(makeKey(in[0], in[1], in[2])).first, static_cast<uint32_t>(2 * i));
    if (rs.exit_tri != kNoTriangle) {
      const auto& out = st_.boundary[rs.exit_tri];
      st_.addWaiter(*st_.faces.tryEmplace(makeKey(out[0], out[1], out[2])).first, static_cast<uint32_t>(2 * i + 1));
    } else {
      // Without an exit triangle the back cursor never waits anywhere: the front covers the segment.
      st_.at_boundary[i] = 2;
    }
  }

 private:
  StreamRenderer::State& st_;
  size_t next_ = 0;
};
}  // namespace

void StreamRenderer::State::release(uint32_t slot) {
  HeldTet& t = tets[slot];
  if (!t.alive()) return;
  for (int k = 0; k < 4; ++k) {
    const uint32_t n = t.nbr[k];
    if (n == kOpenFace) {
      const FaceKey key = t.key(k);
      FaceEntry* e = faces.find(key);
      if (e && e->hasTet() && e->tet() == slot) {
        if (e->waiters == kNoIndex) {
          faces.erase(key);
        } else {
          e->held = kNoIndex;
        }
      }
    } else if (n != kReleasedFace) {
      tets[n >> 2].nbr[n & 3] = kReleasedFace;
    }
  }
  for (int i = 0; i < 4; ++i) {
    PooledVertex* v = t.vertex(i);
    if (--v->refs == 0) unheld.push_back(v);
  }
  t.corner[0] = nullptr;
  tets.free(slot);
  --held;
}

StreamRenderer::StreamRenderer(const RenderOptions& options) : options_(options), state_(std::make_unique<State>()) {}
StreamRenderer::~StreamRenderer() {
  if (state_) state_->waitFlush();
}

Status StreamRenderer::beginLevel(const LevelHeader& header) {
  if (state_) state_->waitFlush();  // a flush still running uses the old state
  state_ = std::make_unique<State>();
  stats_ = StreamRenderStats();
  image_ = Image();
  GTN_ASSIGN_OR_RETURN(state_->reader, ScalarReader::create(header.point_fields, options_.field));
  state_->header = header;
  state_->batch_size = static_cast<size_t>(std::clamp<uint64_t>(header.tets / 64, kMinBatch, kMaxBatch));
  state_->batch.reserve(state_->batch_size);
  state_->flushing.reserve(state_->batch_size);
  state_->phase = State::Phase::kBoundary;
  return Status::ok();
}

Status StreamRenderer::vertex(uint32_t id, const double xyz[3], const uint8_t* values) {
  State& st = *state_;
  if (st.phase != State::Phase::kBoundary && st.phase != State::Phase::kTets)
    return invalidData("renderer: vertex event outside a level");
  const auto [slot, inserted] = st.ids.tryEmplace(id);
  if (!inserted) return invalidData("renderer: vertex " + std::to_string(id) + " emitted twice");
  PooledVertex* v = st.pool.allocate();
  *slot = v;
  for (int i = 0; i < 3; ++i) v->p[i] = xyz[i];
  v->s = st.reader.read(values);
  if (st.shared_frame) shearPoint(st.frame, v->p, v->q);
  v->id = id;
  v->refs = 1;
  stats_.peak_vertices = std::max<uint64_t>(stats_.peak_vertices, st.ids.size());
  return Status::ok();
}

Status StreamRenderer::boundaryTriangle(const uint32_t v[3]) {
  State& st = *state_;
  if (st.phase != State::Phase::kBoundary) return invalidData("renderer: boundary triangle after the boundary ended");
  for (int i = 0; i < 3; ++i)
    if (!st.ids.find(v[i]))
      return invalidData("renderer: boundary triangle " + std::to_string(st.boundary.size()) + " refers to vertex " +
                         std::to_string(v[i]) + " not yet emitted");
  st.boundary.push_back({v[0], v[1], v[2]});
  return Status::ok();
}

Status StreamRenderer::endBoundary() {
  State& st = *state_;
  if (st.phase != State::Phase::kBoundary) return invalidData("renderer: endBoundary out of order");
  // The boundary surface over its own vertices, in local numbering.
  BoundarySurface surface;
  {
    std::unordered_map<uint32_t, uint32_t> local;
    local.reserve(st.boundary.size());
    surface.triangles.reserve(st.boundary.size());
    for (const auto& tri : st.boundary) {
      std::array<uint32_t, 3> t;
      for (int i = 0; i < 3; ++i) {
        auto [it, inserted] = local.emplace(tri[i], static_cast<uint32_t>(surface.points.size()));
        if (inserted) {
          const PooledVertex& v = **st.ids.find(tri[i]);
          surface.points.push_back({v.p[0], v.p[1], v.p[2]});
          surface.scalars.push_back(v.s);
        }
        t[i] = it->second;
      }
      surface.triangles.push_back(t);
    }
  }
  double bmin[3], bmax[3];
  sceneBox(options_, st.header, surface, bmin, bmax);
  setup_ = resolveSetup(options_, bmin, bmax);
  setup_.field = st.reader.description();
  if (!setup_.transfer.has_range) {
    const auto [lo, hi] = boundaryRange(surface);
    setup_.transfer.lo = lo;
    setup_.transfer.hi = hi;
  }
  buildSampleTable(setup_);
  st.shared_frame = setup_.camera.options().projection == Projection::kOrthographic;
  st.frame = prepareRay(setup_.camera.ray(0, 0)).frame;
  if (st.shared_frame) {
    st.ids.forEach([&](uint32_t, PooledVertex* v) { shearPoint(st.frame, v->p, v->q); });
  }
  // Each segment straight into its state, its cursors waiting at its boundary triangles: the
  // segments themselves are never stored together.
  SegmentBuilder builder(st);
  {
    std::vector<uint32_t> pixel_start;
    castBoundary(setup_.camera, surface, &pixel_start, builder, &st.unpaired);
    const size_t pixels = pixel_start.size() - 1;
    st.block_start.resize(pixels / State::kPixelBlock + 1);
    for (size_t b = 0; b < st.block_start.size(); ++b) st.block_start[b] = pixel_start[b * State::kPixelBlock];
    st.pixel_segments.resize(pixels);
    for (size_t p = 0; p < pixels; ++p)
      st.pixel_segments[p] = static_cast<uint8_t>(std::min<uint32_t>(255, pixel_start[p + 1] - pixel_start[p]));
  }
  stats_.segments = st.segs.size() - 1;
  st.boundary.clear();
  st.boundary.shrink_to_fit();
  st.phase = State::Phase::kTets;
  return Status::ok();
}

Status StreamRenderer::tet(const uint32_t v[4], const uint8_t*) {
  State& st = *state_;
  if (st.phase != State::Phase::kTets) return invalidData("renderer: tetrahedron before the end of the boundary");
  ArrivedTet a;
  for (int i = 0; i < 4; ++i) {
    PooledVertex* const* found = st.ids.find(v[i]);
    if (!found)
      return invalidData("renderer: tetrahedron " + std::to_string(stats_.tets) + " refers to vertex " +
                         std::to_string(v[i]) + ", not emitted or already retired");
    a.corner[i] = *found;
  }
  ++stats_.tets;
  st.batch.push_back(a);
  if (st.batch.size() >= st.batch_size) {
    // Render the full batch on another thread while the decoder fills the next one: the decoder only
    // touches the vertex map and `batch`, the flush everything else.
    st.waitFlush();
    GTN_RETURN_IF_ERROR(st.flush_status);
    st.settle();
    std::swap(st.batch, st.flushing);
    st.flush_running = true;
    st.flush_task.run([this] { state_->flush_status = flushBatch(); });
  }
  return Status::ok();
}

Status StreamRenderer::retireVertex(uint32_t id) {
  State& st = *state_;
  PooledVertex* const* found = st.ids.find(id);
  if (!found) return Status::ok();
  st.retired.push_back(*found);
  st.ids.erase(id);
  return Status::ok();
}

namespace {
// The rays of pixel p (segments s0 to s1) whose uncovered part overlaps arrived tetrahedron `a`, by
// the exact crossings.
int32_t exactRayCount(const StreamRenderer::State& st, const Camera& cam, ArrivedTet& a, const TetCorners& g, size_t p,
                      uint32_t s0, uint32_t s1) {
  const PreparedRay ray = st.pixelRay(p, cam);
  double tmin = 1e300, tmax = -1e300;
  Crossing x[4];
  a.computeOrder();
  crossTetFaces(ray, g, -1, x);
  for (int k = 0; k < 4; ++k) {
    if (!x[k].hit) continue;
    tmin = std::min(tmin, x[k].t);
    tmax = std::max(tmax, x[k].t);
  }
  int32_t n = 0;
  if (tmin > tmax) return n;
  for (uint32_t s = s0; s < s1; ++s) {
    const StreamSegment& seg = st.segs[s];
    if (!seg.done() && seg.tf <= tmax && tmin <= seg.tb) ++n;
  }
  return n;
}

// Perspective: the rays of every pixel of the footprint's box, by the exact crossings.
int32_t perspectiveRayCount(const StreamRenderer::State& st, const Camera& cam, ArrivedTet& a, const TetCorners& g,
                            const int box[4]) {
  const int w = cam.width();
  int32_t count = 0;
  for (int py = box[1]; py <= box[3]; ++py) {
    const uint32_t row = static_cast<uint32_t>(py) * w;
    uint32_t s1 = st.firstSegmentFrom(row + box[0]);
    for (int px = box[0]; px <= box[2]; ++px) {
      const uint32_t p = row + px, s0 = s1;
      s1 = st.pixelSegmentsEnd(p, s0);
      if (s0 != s1) count += exactRayCount(st, cam, a, g, p, s0, s1);
    }
  }
  return count;
}

// Orthographic: rasterize the projected tetrahedron row by row. Pixels whose centre lies in its
// projection by a clear margin are hit (the crossing test is watertight), pixels clearly outside are
// not; only those near its outline need the exact crossings. A hit pixel with one segment needs the
// tetrahedron: its cursors cannot have passed a tetrahedron that has not arrived, nor met before it.
// (In an invalid mesh where they did, the tetrahedron is held until the level ends: memory, not the
// image.) Only the pixels' segment counts are read.
int32_t orthographicRayCount(const StreamRenderer::State& st, const Camera& cam, ArrivedTet& a, const TetCorners& g,
                             const int box[4], const double sx[4], const double sy[4]) {
  constexpr double kSure = ScreenHull::kSure;  // rounding differences are about 1e-10 pixels
  const int w = cam.width();
  const ScreenHull hull(sx, sy, 4);
  const uint8_t* nseg = st.pixel_segments.data();
  int32_t count = 0;
  for (int py = box[1]; py <= box[3]; ++py) {
    const double yc = py + 0.5;
    // The projection's span on this row. Only the pixels within kSure of it can fail the "clearly
    // outside" test below: two thirds of a footprint's box are skipped unread.
    double xl, xr;
    const bool row_inside = hull.span(yc, kSure, &xl, &xr);
    int px0 = box[0], px1 = box[2];
    if (row_inside) ScreenHull::columns(xl, xr, kSure, box, &px0, &px1);
    const uint32_t row = static_cast<uint32_t>(py) * w;
    for (int px = px0; px <= px1; ++px) {
      const uint32_t p = row + px;
      const uint8_t n = nseg[p];
      if (n == 0) continue;
      const double xc = px + 0.5;
      if (row_inside && (xc < xl - kSure || xc > xr + kSure)) continue;  // clearly outside
      if (row_inside && n == 1 && xc > xl + kSure && xc < xr - kSure) {  // clearly inside
        ++count;
        continue;
      }
      const uint32_t s0 = st.firstSegmentFrom(p);
      count += exactRayCount(st, cam, a, g, p, s0, st.pixelSegmentsEnd(p, s0));
    }
  }
  return count;
}

// Step 1: how many rays still need each arrived tetrahedron (parallel; segments are read only).
void countRays(StreamRenderer::State& st, const Camera& cam) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, st.flushing.size(), 16), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      ArrivedTet& a = st.flushing[i];
      a.rays = 0;
      a.visible = false;
      // The faces' canonical orders are computed only for the exact crossings and for a tetrahedron
      // that will be held: most arrived tetrahedra need neither.
      a.order[0][0] = kNoOrder;
      const double* corners[4] = {a.corner[0]->p, a.corner[1]->p, a.corner[2]->p, a.corner[3]->p};
      int box[4];
      double sx[4], sy[4];
      if (!pixelFootprint(cam, corners, 4, box, sx, sy)) continue;
      a.visible = true;
      // Orthographic: the corners' sheared positions (the pool's, computed once per vertex).
      const TetCorners g{a.corner, a.order, st.shared_frame};
      a.rays =
          st.shared_frame ? orthographicRayCount(st, cam, a, g, box, sx, sy) : perspectiveRayCount(st, cam, a, g, box);
      if (a.rays > 0) a.computeOrder();
    }
  });
}

// Whether arrived tetrahedron `a` must be held: a ray needs it, or a cursor waits at one of its
// faces (`keys`, filled).
bool tetNeeded(const StreamRenderer::State& st, const ArrivedTet& a, FaceKey keys[4]) {
  bool needed = a.rays > 0;
  for (int k = 0; k < 4; ++k) {
    keys[k] = makeKey(a.vertex(kTetFace[k][0])->id, a.vertex(kTetFace[k][1])->id, a.vertex(kTetFace[k][2])->id);
    if (!needed) {
      const FaceEntry* e = st.faces.find(keys[k]);
      if (e && e->waiters != kNoIndex) needed = true;
    }
  }
  return needed;
}

// Holds `a` in a new slot, links it to the held neighbours found at its faces `keys`, and triggers
// the cursors waiting there. Returns the slot.
uint32_t holdTet(StreamRenderer::State& st, ArrivedTet& a, const FaceKey keys[4]) {
  const uint32_t slot = st.tets.allocate();
  HeldTet& t = st.tets[slot];
  for (int k = 0; k < 4; ++k) {
    t.corner[k] = a.corner[k];
    ++a.vertex(k)->refs;
    t.nbr[k] = kOpenFace;
  }
  a.computeOrder();  // held for its waiters alone
  std::memcpy(t.order, a.order, sizeof(t.order));
  t.pending.store(a.rays, std::memory_order_relaxed);
  ++st.held;
  for (int k = 0; k < 4; ++k) {
    const auto [entry, inserted] = st.faces.tryEmplace(keys[k]);
    FaceEntry& e = *entry;
    if (inserted) {
      e.setTet(slot, k);
      continue;
    }
    st.takeWaiters(e, [&](uint32_t c) {
      st.cursor_word[c] = heldFace(slot, k);
      st.trigger(c);
    });
    if (e.hasTet() && e.tet() != slot) {
      st.tets[e.tet()].nbr[e.face()] = heldFace(slot, k);
      t.nbr[k] = e.held;
      st.faces.erase(keys[k]);
    } else {
      e.setTet(slot, k);
    }
  }
  return slot;
}

// Step 2: hold the tetrahedra some ray needs, link them to held neighbours, collect the cursors
// waiting at their faces (sequential: the face map). The slots held go to st.arrived_slots.
Status holdNeededTets(StreamRenderer::State& st, StreamRenderStats& stats) {
  st.trigger_segs.clear();
  st.arrived_slots.clear();
  for (ArrivedTet& a : st.flushing) {
    // Most tetrahedra of a large mesh lie between pixel centres: nothing to look up for them.
    if (!a.visible) continue;
    FaceKey keys[4];
    if (!tetNeeded(st, a, keys)) continue;
    if (st.held >= kMaxHeldSlots)
      return invalidData("renderer: more than " + std::to_string(kMaxHeldSlots) + " tetrahedra held at once");
    st.arrived_slots.push_back(holdTet(st, a, keys));
    ++stats.tets_held;
  }
  stats.peak_tets_held = std::max(stats.peak_tets_held, st.held);
  return Status::ok();
}

// Advances the triggered cursors of segment `si` (the front first) through the held tetrahedra,
// then stores the segment's colours; cursors that stop at an open face go to `waits`.
void advanceSegment(StreamRenderer::State& st, const RenderSetup& setup, HeldMesh& mesh, uint32_t si,
                    std::vector<uint32_t>& waits) {
  const uint8_t which = st.triggered[si];
  st.triggered[si] = 0;
  StreamSegment& seg = st.segs[si];
  const PreparedRay ray = st.pixelRay(seg.pixel, setup.camera);
  // The colours in double while the segment's cursors advance.
  Rgba front_colour = seg.front.get();
  Rgba back_colour = seg.back != kNoIndex ? st.backs[seg.back].get() : Rgba();
  // A cursor that stopped (met, boundary, lost) waits nowhere, so only waiting cursors come here;
  // the back one may find its segment done by the front meanwhile.
  for (uint32_t end = 0; end < 2; ++end) {
    if (!(which >> end & 1) || seg.done()) continue;
    const uint32_t cursor = 2 * si + end;
    const uint32_t enter = st.cursor_word[cursor];
    const bool front = end == 0;
    uint32_t wait_tet = 0;
    int wait_face = 0;
    Rgba& colour = front ? front_colour : back_colour;
    const CursorEnd end_state = advanceCursor(setup, ray, seg, front, colour, enter >> 2, static_cast<int>(enter & 3),
                                              mesh, &wait_tet, &wait_face);
    if (end_state == CursorEnd::kWait) {
      st.cursor_word[cursor] = heldFace(wait_tet, wait_face);
      waits.push_back(cursor);
    } else if (end_state == CursorEnd::kLost) {
      st.lost.fetch_add(1, std::memory_order_relaxed);
    } else if (end_state == CursorEnd::kBoundary) {
      st.at_boundary[si] |= static_cast<uint8_t>(1u << end);
    }
  }
  if (seg.done()) {
    seg.front = StoredRgba(over(front_colour, back_colour));
    if (seg.back != kNoIndex) st.backs.free(seg.back);
    seg.back = kNoIndex;
  } else {
    seg.front = StoredRgba(front_colour);
    if (seg.back != kNoIndex) {
      st.backs[seg.back] = StoredRgba(back_colour);
    } else if (!isBlank(back_colour)) {
      seg.back = st.backs.allocate(StoredRgba(back_colour));
    }
  }
}

// Step 3: advance the triggered cursors (parallel over segments; a segment's cursors in one task).
// Segments do not interact within a batch (nothing is released before step 5), so the order of the
// segments does not matter.
void advanceTriggered(StreamRenderer::State& st, const RenderSetup& setup) {
  for (auto& list : st.zeroed) list.clear();
  for (auto& list : st.waits) list.clear();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, st.trigger_segs.size(), 8), [&](const tbb::blocked_range<size_t>& r) {
    HeldMesh mesh{st, st.zeroed};
    std::vector<uint32_t>& my_waits = st.waits.local();
    for (size_t i = r.begin(); i < r.end(); ++i) advanceSegment(st, setup, mesh, st.trigger_segs[i], my_waits);
  });
}

// Step 4: the cursors now waiting at open faces of held tetrahedra join those faces' waiter lists.
void parkWaitingCursors(StreamRenderer::State& st, StreamRenderStats& stats) {
  for (const std::vector<uint32_t>& list : st.waits) {
    for (const uint32_t cursor : list) {
      const uint32_t slot = st.cursor_word[cursor] >> 2;
      const int face = static_cast<int>(st.cursor_word[cursor] & 3);
      const auto [e, inserted] = st.faces.tryEmplace(st.tets[slot].key(face));
      if (inserted) e->setTet(slot, face);
      st.addWaiter(*e, cursor);
    }
  }
  stats.peak_face_entries = std::max<uint64_t>(stats.peak_face_entries, st.faces.size());
}

// Step 5: release what no ray needs any more.
void releaseUnneeded(StreamRenderer::State& st) {
  for (const std::vector<uint32_t>& list : st.zeroed)
    for (uint32_t slot : list)
      if (st.tets[slot].pending.load(std::memory_order_relaxed) <= 0) st.release(slot);
  for (uint32_t slot : st.arrived_slots)
    if (st.tets[slot].alive() && st.tets[slot].pending.load(std::memory_order_relaxed) <= 0) st.release(slot);
}
}  // namespace

// Renders the batch `flushing` in five steps: count the rays each tetrahedron meets, hold those
// needed, advance the cursors they trigger, park the cursors that wait, release what no ray needs.
Status StreamRenderer::flushBatch() {
  State& st = *state_;
  if (st.flushing.empty()) return Status::ok();
  countRays(st, setup_.camera);
  GTN_RETURN_IF_ERROR(holdNeededTets(st, stats_));
  advanceTriggered(st, setup_);
  parkWaitingCursors(st, stats_);
  releaseUnneeded(st);
  return Status::ok();
}

Status StreamRenderer::endLevel() {
  State& st = *state_;
  if (st.phase == State::Phase::kBoundary) GTN_RETURN_IF_ERROR(endBoundary());
  if (st.phase != State::Phase::kTets) return invalidData("renderer: endLevel out of order");
  st.waitFlush();
  GTN_RETURN_IF_ERROR(st.flush_status);
  st.settle();
  std::swap(st.batch, st.flushing);
  GTN_RETURN_IF_ERROR(flushBatch());
  const int w = setup_.camera.width(), h = setup_.camera.height();
  image_ = Image(w, h);
  uint32_t s = 0;
  size_t next_unpaired = 0;
  for (size_t p = 0; p < static_cast<size_t>(w) * h; ++p) {
    Rgba acc;
    bool lost = next_unpaired < st.unpaired.size() && st.unpaired[next_unpaired] == p;
    next_unpaired += lost;
    for (; st.segs[s].pixel == p; ++s) {
      const StreamSegment& seg = st.segs[s];
      acc = over(acc, over(seg.front.get(), seg.back != kNoIndex ? st.backs[seg.back].get() : Rgba()));
      lost |= !seg.done() && st.at_boundary[s] != 3;
    }
    stats_.lost_rays += lost;
    toRgb8(acc, &image_.rgb[3 * p]);
  }
  stats_.lost_cursors = st.lost.load();
  stats_.tets_left_held = st.held;
  state_ = std::make_unique<State>();
  state_->phase = State::Phase::kDone;
  return Status::ok();
}

}  // namespace gtn
