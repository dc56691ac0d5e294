#include "path/minimal_construct.hpp"

#include "geometry/predicates.hpp"

#include "geometry/polygon.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

namespace staa {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::uint32_t kNoPolygon = std::numeric_limits<std::uint32_t>::max();


// Equal to the bit (0.0 and -0.0 apart): a kept answer is reused only for the very same input.
bool sameBits(const Vec2& a, const Vec2& b) { return std::memcmp(a.data(), b.data(), 2 * sizeof(double)) == 0; }

std::uint64_t edgeKey(std::int32_t a, std::int32_t b) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

std::size_t hashKey(std::uint64_t k) {
  k ^= k >> 33;
  k *= 0xff51afd7ed558ccdULL;
  k ^= k >> 33;
  return static_cast<std::size_t>(k);
}

}  // namespace

void MinimalConstruct::setStaticObstacles(std::span<const Polygon> polygons) {
  PolygonSet::Options opt;
  opt.cell_size = options_.grid_cell_m;
  static_.assign(polygons, opt);
  horizon_.clear();
  horizon_tests_ = 0;
  dynamic_.reserve(options_.max_dynamic_polygons, options_.max_dynamic_vertices);
  dynamic_.clear();
  static_discovered_.assign(static_.polygonCount(), 0);
  dynamic_discovered_.assign(options_.max_dynamic_polygons, 0);
  const std::size_t max_nodes = static_.vertexCount() + options_.max_dynamic_vertices + 2;
  nodes_.reserve(max_nodes);
  tangency_ = use_tangency_table_ ? TangencyTable::forSet(static_) : nullptr;
  corner_node_.assign(tangency_ ? tangency_->corners() : 0, kNone);
  other_nodes_.clear();
  other_nodes_.reserve(max_nodes);
  target_blocked_.clear();
  target_blocked_.reserve(max_nodes);
  heap_.reserve(max_nodes);
  open_scan_.reserve(max_nodes);
  open_scan_valid_ = false;
  closed_.reserve(max_nodes);
  // Written once, so that its pages are mapped now: it is first filled inside a cycle, at a
  // start's first blocked edge, where a page fault on a first touch would stall the cycle.
  start_candidates_.assign(max_nodes, StartCandidate{});
  start_candidates_.clear();
  closed_corner_.reserve(max_nodes);
  path_.reserve(max_nodes + 2);
  blockers_.assign(static_.polygonCount() + options_.max_dynamic_polygons, 0);
  covering_.assign(static_.polygonCount() + options_.max_dynamic_polygons, 0);
  pending_.clear();
  pending_.reserve(static_.polygonCount() + options_.max_dynamic_polygons);
  rediscover_.clear();
  rediscover_.reserve(static_.polygonCount());
  std::size_t slots = 1024;
  while (slots < 4 * max_nodes) slots *= 2;
  blocked_keys_.assign(slots, 0);
  blocked_gen_.assign(slots, 0);
  blocked_generation_ = 1;
  have_goal_ = false;
  tree_valid_ = false;
  goal_free_valid_ = false;
  // Which static polygons cover each static corner never changes: find out once.
  static_cover_offsets_.assign(static_.vertexCount() + 1, 0);
  static_cover_.clear();
  for (std::size_t v = 0; v < static_.vertexCount(); ++v) {
    if (static_.isConvexCorner(v)) {
      const std::size_t n = static_.coveringPolygons(static_.vertex(v), static_.polygonOfVertex(v), covering_);
      static_cover_.insert(static_cover_.end(), covering_.begin(), covering_.begin() + static_cast<std::ptrdiff_t>(n));
    }
    static_cover_offsets_[v + 1] = static_cast<std::uint32_t>(static_cover_.size());
  }
  total_discovered_ = 0;
}

void MinimalConstruct::setDynamicObstacles(std::span<const PolygonView> polygons) {
  // Keep within the reserved capacity: drop what does not fit rather than allocate.
  std::size_t n = 0, verts = 0;
  for (const PolygonView& p : polygons) {
    if (n == options_.max_dynamic_polygons || verts + p.size() > options_.max_dynamic_vertices) break;
    ++n;
    verts += p.size();
  }
  dropped_dynamic_ = polygons.size() - n;
  dynamic_.assign(polygons.first(n), PolygonSet::Options{});
  goal_free_valid_ = false;
  if (tree_with_dynamic_) tree_valid_ = false;  // the kept tree saw the old dynamic obstacles
}

void MinimalConstruct::clearDynamicObstacles() {
  if (tree_with_dynamic_ && dynamic_.polygonCount() > 0) tree_valid_ = false;
  dynamic_.clear();
  dropped_dynamic_ = 0;
  goal_free_valid_ = false;
}

bool MinimalConstruct::pointFree(const Vec2& p, bool with_dynamic) const {
  const bool static_free = (oracle_ != nullptr && oracle_(oracle_context_, p, p)) || !static_.pointBlocked(p);
  return static_free && !(with_dynamic && dynamic_.pointBlocked(p));
}

bool MinimalConstruct::segmentFree(const Vec2& a, const Vec2& b, bool with_dynamic) const {
  return !static_.segmentBlocked(a, b) && !(with_dynamic && dynamic_.segmentBlocked(a, b));
}

bool MinimalConstruct::nearestFreePoint(const Vec2& p, bool with_dynamic, Vec2& out) const {
  if (pointFree(p, with_dynamic)) {
    out = p;
    return true;
  }
  // The free point nearest to p lies on some polygon's boundary. Search boxes of growing
  // radius R around p: every edge within distance R of p is found through the edge index,
  // its closest point is a candidate, and candidates are tried nearest first. A candidate
  // that no other polygon covers (once nudged away from p) is the answer; only candidates
  // within R count, so the first success is the true nearest. Fixed buffers: no allocation.
  const Box ext = static_.extent();
  double radius = 0.25;
  for (int round = 0; round < 40; ++round, radius *= 2.0) {
    const Box box{p - Vec2(radius, radius), p + Vec2(radius, radius)};
    std::size_t count = 0;
    auto consider = [&](const PolygonSet& set, std::size_t v) {
      const Vec2& a = set.vertex(v);
      const Vec2& b = set.vertex(set.nextVertex(v));
      const Vec2 q = closestPointOnSegment(p, a, b);
      const double d = (q - p).norm();
      if (d > radius) return false;
      // Insertion into the sorted buffer; when full, the farthest candidate is dropped (the
      // round then cannot prove optimality and the next, larger round repeats the search).
      std::size_t i = std::min(count, candidates_.size() - 1);
      if (count == candidates_.size() && d >= candidates_.back().distance) {
        overflow_ = true;
        return false;
      }
      if (count == candidates_.size()) overflow_ = true;
      while (i > 0 && candidates_[i - 1].distance > d) {
        candidates_[i] = candidates_[i - 1];
        --i;
      }
      candidates_[i] = Candidate{q, b - a, d};
      count = std::min(count + 1, candidates_.size());
      return false;
    };
    overflow_ = false;
    static_.forEachEdgeInBox(box, [&](std::size_t v) { return consider(static_, v); });
    if (with_dynamic) dynamic_.forEachEdgeInBox(box, [&](std::size_t v) { return consider(dynamic_, v); });
    for (std::size_t i = 0; i < count; ++i) {
      const Candidate& c = candidates_[i];
      Vec2 dir = c.point - p;
      const double len = dir.norm();
      dir = len > 0.0 ? Vec2(dir / len) : Vec2(Vec2(c.edge.y(), -c.edge.x()).normalized());
      const Vec2 candidate = c.point + 1e-6 * dir;
      if (pointFree(candidate, with_dynamic)) {
        out = candidate;
        return true;
      }
    }
    const bool covers_all = box.contains(ext.min) && box.contains(ext.max) &&
                            (!with_dynamic || (box.contains(dynamic_.extent().min) && box.contains(dynamic_.extent().max)));
    if (covers_all && !overflow_) break;  // every edge was a candidate: nothing is free
  }
  return false;
}

void MinimalConstruct::resetSearch(const Vec2& goal, bool with_dynamic) {
  // Polygons discovered for the same goal are known to matter: keep them.
  if (!have_goal_ || goal != goal_pos_) {
    std::fill(static_discovered_.begin(), static_discovered_.end(), 0);
    goal_pos_ = goal;
    have_goal_ = true;
  }
  tree_valid_ = false;
  std::fill(dynamic_discovered_.begin(), dynamic_discovered_.end(), 0);
  nodes_.clear();
  std::fill(corner_node_.begin(), corner_node_.end(), kNone);
  other_nodes_.clear();
  heap_.clear();
  open_scan_valid_ = false;
  closed_.clear();
  closed_corner_.clear();
  if (++blocked_generation_ == 0) {
    std::fill(blocked_gen_.begin(), blocked_gen_.end(), 0);
    blocked_generation_ = 1;
  }
  blocked_count_ = 0;
  total_discovered_ = 0;
  nodes_.push_back(Node{});  // 0: the goal, root of the backward search
  Node target;               // 1: the start, the search's target, replaced by every query
  target.state = kClosed;    // (not a node of the graph until a query places it)
  nodes_.push_back(target);
  // The kept polygons join the new graph: list them, clear the marks, discover them again
  // (discovering one may bring in others, which are then not added twice).
  rediscover_.clear();
  for (std::size_t k = 0; k < static_discovered_.size(); ++k) {
    if (static_discovered_[k]) rediscover_.push_back(static_cast<std::uint32_t>(k));
  }
  std::fill(static_discovered_.begin(), static_discovered_.end(), 0);
  for (const std::uint32_t k : rediscover_) discoverPolygon(k, with_dynamic);
}

bool MinimalConstruct::markDiscovered(std::uint32_t global_polygon) {
  const auto ns_poly = static_cast<std::uint32_t>(static_.polygonCount());
  std::uint8_t& flag = global_polygon < ns_poly ? static_discovered_[global_polygon]
                                                : dynamic_discovered_[global_polygon - ns_poly];
  if (flag) return false;
  flag = 1;
  ++total_discovered_;
  return true;
}

void MinimalConstruct::discoverPolygon(std::uint32_t global_polygon, bool with_dynamic) {
  // A worklist, not recursion: overlapping polygons can form long chains. A polygon is marked
  // when it is queued, so it is queued once and the list never outgrows its reserve.
  if (!markDiscovered(global_polygon)) return;
  pending_.push_back(global_polygon);
  while (!pending_.empty()) {
    const std::uint32_t k = pending_.back();
    pending_.pop_back();
    discoverOne(k, with_dynamic);
  }
}

void MinimalConstruct::discoverOne(std::uint32_t global_polygon, bool with_dynamic) {
  const auto ns_poly = static_cast<std::uint32_t>(static_.polygonCount());
  const bool is_static = global_polygon < ns_poly;
  const std::uint32_t local = is_static ? global_polygon : global_polygon - ns_poly;
  const PolygonSet& set = is_static ? static_ : dynamic_;
  const PolygonView poly = set.polygon(local);
  const std::size_t first = static_cast<std::size_t>(poly.data() - &set.vertex(0));
  const std::size_t offset = is_static ? 0 : static_.vertexCount();
  const std::size_t first_new = nodes_.size();
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const std::size_t v = first + i;
    // Only convex corners in free space can be turning points of a shortest path.
    if (!set.isConvexCorner(v)) continue;
    const Vec2& p = set.vertex(v);
    // A corner inside another polygon is not a node, but that polygon bounds the free space
    // right here, so it joins the graph too: without it, the way around both is missing.
    bool covered = false;
    if (is_static) {
      for (std::uint32_t j = static_cover_offsets_[v]; j < static_cover_offsets_[v + 1]; ++j) {
        covered = true;
        if (markDiscovered(static_cover_[j])) pending_.push_back(static_cover_[j]);
      }
    } else {
      const std::size_t n = static_.coveringPolygons(p, kNoPolygon, covering_);
      for (std::size_t j = 0; j < n; ++j) {
        covered = true;
        if (markDiscovered(covering_[j])) pending_.push_back(covering_[j]);
      }
    }
    if (with_dynamic) {
      const std::size_t n = dynamic_.coveringPolygons(p, is_static ? kNoPolygon : local, covering_);
      for (std::size_t j = 0; j < n; ++j) {
        covered = true;
        if (markDiscovered(covering_[j] + ns_poly)) pending_.push_back(covering_[j] + ns_poly);
      }
    }
    if (covered) continue;
    Node node;
    node.pos = p;
    node.prev = set.vertex(set.prevVertex(v));
    node.next = set.vertex(set.nextVertex(v));
    node.vertex = static_cast<std::int32_t>(v + offset);
    nodes_.push_back(node);
    const auto id = static_cast<std::int32_t>(nodes_.size() - 1);
    const std::int32_t corner = staticCorner(node);
    if (corner >= 0) {
      corner_node_[static_cast<std::size_t>(corner)] = id;
    } else if (tangency_) {
      other_nodes_.push_back(id);
    }
  }
  // Connect the new corners to everything already closed (the repair step).
  for (std::size_t n = first_new; n < nodes_.size(); ++n) {
    relaxFromClosed(static_cast<std::int32_t>(n), /*in_heap=*/true);
  }
}

bool MinimalConstruct::canFollow(std::int32_t from, std::int32_t to) const {
  const Node& a = nodes_[static_cast<std::size_t>(from)];
  const Node& b = nodes_[static_cast<std::size_t>(to)];
  // Two static corners: both tangency tests from the table (the same exact answers). `to`
  // first: in the warm queries it is the start, and the lookups cost nothing then.
  const std::int32_t cb = staticCorner(b), ca = cb >= 0 ? staticCorner(a) : -1;
  const bool tangents_known = ca >= 0;
  if (tangents_known && !tangency_->joinable(ca, cb)) return false;
  if (a.vertex != kNone) {
    if (!tangents_known && !tangentAt(a.pos, b.pos, a.prev, a.next, orient_bound_)) return false;
    // The path must turn around the corner, towards the side the polygon lies on.
    if (a.turn != 0) {
      const int turn = orientSign(nodes_[static_cast<std::size_t>(a.parent)].pos, a.pos, b.pos, orient_bound_);
      if (turn != 0 && turn != a.turn) return false;
    }
  }
  return tangents_known || b.vertex == kNone || tangentAt(b.pos, a.pos, b.prev, b.next, orient_bound_);
}

// Forced inline: repairParent runs it over the whole closed list for every blocked edge,
// and a call per closed node (registers saved and restored) outweighs the test itself.
[[gnu::always_inline]] inline bool MinimalConstruct::improve(std::int32_t from, std::int32_t to) {
  Node& b = nodes_[static_cast<std::size_t>(to)];
  const Node& a = nodes_[static_cast<std::size_t>(from)];
  const double g = a.g + (b.pos - a.pos).norm();
  if (b.state == kOpen && g >= b.g) return false;
  if (!canFollow(from, to) || edgeKnownBlocked(from, to)) return false;
  b.g = g;
  b.f = g + (target_pos_ - b.pos).norm();
  b.parent = from;
  return true;
}

[[gnu::always_inline]] inline void MinimalConstruct::relax(std::int32_t from, std::int32_t to) {
  Node& b = nodes_[static_cast<std::size_t>(to)];
  if (b.state == kClosed || !improve(from, to)) return;
  if (b.state == kOpen) {
    heapDecrease(to);
  } else {
    b.state = kOpen;
    heapPush(to);
  }
}

// Forced inline as relax: the re-attach runs it over the whole closed list.
[[gnu::always_inline]] inline void MinimalConstruct::relaxOutsideHeap(std::int32_t from, std::int32_t to) {
  if (improve(from, to)) nodes_[static_cast<std::size_t>(to)].state = kOpen;
}

void MinimalConstruct::expand(std::int32_t v) {
  // relax(v, w) for every node, with v's data hoisted and the cheap rejections first: most
  // candidates fail a tangency test, so the distance (a square root) is computed for few.
  // Which node is relaxed first changes nothing: each is relaxed from v alone, and the heap
  // pops in a strict order (f, g, id).
  const Node& a = nodes_[static_cast<std::size_t>(v)];
  const Vec2 pa = a.pos, prev = a.prev, next = a.next;
  const bool corner = a.vertex != kNone;
  const int turn = a.turn;
  const Vec2 pu = turn != 0 ? nodes_[static_cast<std::size_t>(a.parent)].pos : pa;
  const double ga = a.g;
  const double bound = orient_bound_;
  // tangents_known: w passed both tangency tests (the table's row). Inlined into each loop (a
  // call per node costs more than most nodes' tests).
  const auto relaxFromV = [&](std::size_t w, bool tangents_known) __attribute__((always_inline)) {
    Node& b = nodes_[w];
    if (b.state == kClosed) return;
    if (corner) {
      if (!tangents_known && !tangentAt(pa, b.pos, prev, next, bound)) return;
      if (turn != 0) {
        const int t = orientSign(pu, pa, b.pos, bound);
        if (t != 0 && t != turn) return;
      }
    }
    if (!tangents_known && b.vertex != kNone && !tangentAt(b.pos, pa, b.prev, b.next, bound)) return;
    const double g = ga + (b.pos - pa).norm();
    if (b.state == kOpen && g >= b.g) return;
    const auto to = static_cast<std::int32_t>(w);
    if (edgeKnownBlocked(v, to)) return;
    b.g = g;
    b.f = g + (target_pos_ - b.pos).norm();
    b.parent = v;
    if (b.state == kOpen) {
      heapDecrease(to);
    } else {
      b.state = kOpen;
      heapPush(to);
    }
  };
  // The row when it lists fewer corners than the search has nodes (a search that discovered
  // little of the map tests its few nodes faster).
  const std::int32_t row_corner = staticCorner(a);
  if (row_corner < 0 || tangency_->rowCount(row_corner) >= nodes_.size()) {
    const std::size_t n = nodes_.size();
    for (std::size_t w = 0; w < n; ++w) relaxFromV(w, false);
    return;
  }
  relaxFromV(0, false);
  if (nodes_.size() > 1) relaxFromV(1, false);
  for (const std::int32_t w : other_nodes_) relaxFromV(static_cast<std::size_t>(w), false);
  const std::span<const std::uint64_t> row = tangency_->row(row_corner);
  for (std::size_t word = 0; word < row.size(); ++word) {
    for (std::uint64_t bits = row[word]; bits != 0; bits &= bits - 1) {
      const std::size_t c = 64 * word + static_cast<std::size_t>(std::countr_zero(bits));
      const std::int32_t w = corner_node_[c];
      if (w != kNone) relaxFromV(static_cast<std::size_t>(w), true);
    }
  }
}

void MinimalConstruct::repairParent(std::int32_t node, bool in_heap) {
  Node& n = nodes_[static_cast<std::size_t>(node)];
  n.state = kUnseen;
  n.parent = kNone;
  n.g = kInf;
  relaxFromClosed(node, in_heap);
}

void MinimalConstruct::relaxFromClosed(std::int32_t node, bool in_heap) {
  const std::int32_t corner = staticCorner(nodes_[static_cast<std::size_t>(node)]);
  if (corner < 0) {
    if (in_heap) {
      for (const std::int32_t c : closed_) relax(c, node);
    } else {
      for (const std::int32_t c : closed_) relaxOutsideHeap(c, node);
    }
    return;
  }
  const std::uint64_t* row = tangency_->row(corner).data();
  for (std::size_t i = 0; i < closed_.size(); ++i) {
    const std::int32_t cc = closed_corner_[i];
    if (cc >= 0 && ((row[static_cast<std::size_t>(cc) >> 6] >> (static_cast<std::size_t>(cc) & 63)) & 1U) == 0) continue;
    if (in_heap) {
      relax(closed_[i], node);
    } else {
      relaxOutsideHeap(closed_[i], node);
    }
  }
}

bool MinimalConstruct::edgeKnownBlocked(std::int32_t a, std::int32_t b) const {
  if (a == kTarget || b == kTarget) {
    const std::int32_t other = a == kTarget ? b : a;
    return std::find(target_blocked_.begin(), target_blocked_.end(), other) != target_blocked_.end();
  }
  if (blocked_count_ == 0) return false;
  const std::uint64_t key = edgeKey(a, b);
  const std::size_t mask = blocked_keys_.size() - 1;
  for (std::size_t i = hashKey(key) & mask;; i = (i + 1) & mask) {
    if (blocked_gen_[i] != blocked_generation_) return false;
    if (blocked_keys_[i] == key) return true;
  }
}

void MinimalConstruct::markEdgeBlocked(std::int32_t a, std::int32_t b) {
  if (a == kTarget || b == kTarget) {
    // Edges into the start change meaning with every query: kept apart, cleared per query.
    if (target_blocked_.size() < target_blocked_.capacity()) target_blocked_.push_back(a == kTarget ? b : a);
    return;
  }
  if (2 * (blocked_count_ + 1) > blocked_keys_.size()) {
    // Pathological: more failed edges than four per node. Grow (allocates) rather than loop.
    std::vector<std::uint64_t> keys;
    for (std::size_t i = 0; i < blocked_keys_.size(); ++i) {
      if (blocked_gen_[i] == blocked_generation_) keys.push_back(blocked_keys_[i]);
    }
    blocked_keys_.assign(blocked_keys_.size() * 2, 0);
    blocked_gen_.assign(blocked_gen_.size() * 2, 0);
    blocked_count_ = 0;
    for (const std::uint64_t k : keys) {
      markEdgeBlocked(static_cast<std::int32_t>(k >> 32), static_cast<std::int32_t>(k & 0xffffffffU));
    }
  }
  const std::uint64_t key = edgeKey(a, b);
  const std::size_t mask = blocked_keys_.size() - 1;
  for (std::size_t i = hashKey(key) & mask;; i = (i + 1) & mask) {
    if (blocked_gen_[i] != blocked_generation_) {
      blocked_gen_[i] = blocked_generation_;
      blocked_keys_[i] = key;
      ++blocked_count_;
      return;
    }
    if (blocked_keys_[i] == key) return;
  }
}

std::int32_t MinimalConstruct::addTargetNode(const Vec2& start) {
  Node node;
  node.pos = start;
  node.g = kInf;
  nodes_[kTarget] = node;
  target_blocked_.clear();  // blocked edges into the previous start are about another point
  target_pos_ = start;
  return kTarget;
}

MinimalConstruct::StartStep MinimalConstruct::startIsNextPop(bool use_dynamic, Result& result) {
  Node& t = nodes_[static_cast<std::size_t>(target_)];
  if (t.state != kOpen) return StartStep::kNotNext;
  // Is some open node's true key g + |node - start| below the start's g? The heap's keys
  // were made for the anchor; moving the start by |start - anchor| lowers no true key by
  // more than that, so the top key minus it bounds them all (no scan). Else scan: only
  // nodes with g below the start's can be lower, and no square root is needed.
  double top = kInf;
  for (std::size_t i = 0; i < std::min<std::size_t>(3, heap_.size()); ++i) {
    if (heap_[i] != target_) top = std::min(top, nodes_[static_cast<std::size_t>(heap_[i])].f);
  }
  bool lower = t.g > top - (target_pos_ - key_anchor_).norm();
  if (lower) {
    lower = false;
    // The open nodes but the start, copied out of the node pool while the heap keeps them
    // (queries between two pops scan the same ones).
    if (!open_scan_valid_) {
      open_scan_.clear();
      for (const std::int32_t n : heap_) {
        if (n != target_) open_scan_.push_back(ScanEntry{nodes_[static_cast<std::size_t>(n)].pos, nodes_[static_cast<std::size_t>(n)].g});
      }
      open_scan_valid_ = true;
    }
    for (const ScanEntry& o : open_scan_) {
      const double slack = t.g - o.g;
      if (slack <= 0.0) continue;
      if ((target_pos_ - o.pos).squaredNorm() < slack * slack) {
        lower = true;
        break;
      }
    }
  }
  if (lower) return StartStep::kNotNext;
  // The edge's blockers at once (what the search's edge check would list), not a yes/no
  // test followed by the same walk again when the edge is blocked.
  start_blockers_ = edgeBlockers(target_, use_dynamic);
  if (start_blockers_ > 0) return StartStep::kBlocked;
  t.state = kClosed;
  closed_.push_back(target_);
  closed_corner_.push_back(-1);
  ++result.expansions;
  return StartStep::kFound;
}

bool MinimalConstruct::reattachStart(const Vec2& start, bool use_dynamic, const Deadline& deadline,
                                     std::uint32_t& until_check, Result& result) {
  // Retire the previous start: it was never expanded, so nothing hangs below it, and its
  // node takes the new start.
  if (nodes_[kTarget].state == kOpen) heapRemove(kTarget);
  if (!closed_.empty() && closed_.back() == kTarget) {
    closed_.pop_back();
    closed_corner_.pop_back();
  }
  target_ = addTargetNode(start);
  // The start stays out of the heap until the search needs it there: the test below excludes
  // it anyway, and the heap pops in a strict order (f, g, id), so where it sat changes no pop.
  for (const std::int32_t c : closed_) relaxOutsideHeap(c, target_);
  start_candidates_heap_ = false;
  // The common case, without touching the heap: the new start's best connection to the
  // tree is at least as short as anything still open (true keys, computed by a scan) and
  // its edge is free. Then it would be the next pop of a re-keyed heap, and is the answer.
  // When that edge is blocked, the search's own step is taken here (the pop of the start,
  // its blockers discovered, the start re-parented through the next best closed node) and
  // the test repeated: the open list is re-keyed only when another node would pop first.
  for (bool first = true;; first = false) {
    const StartStep step = startIsNextPop(use_dynamic, result);
    if (step == StartStep::kFound) return true;
    if (step == StartStep::kNotNext) break;
    // search()'s deadline check before this pop, on the same count.
    if (until_check-- == 0) {
      if (deadline.passed()) {
        until_check = 0;
        break;
      }
      until_check = 15;
    }
    // The search checked the first start edge again after this test (counted as it did);
    // later tests stand for the search's own checks.
    if (first) ++edge_checks_;
    // blockedEdgeInto(target_, ..., in_heap = false), the new parent from the candidates.
    markEdgeBlocked(nodes_[kTarget].parent, target_);
    for (std::size_t i = 0; i < start_blockers_; ++i) discoverPolygon(blockers_[i], use_dynamic);
    nextStartParent();
  }
  if (nodes_[static_cast<std::size_t>(target_)].state == kOpen) heapPush(target_);
  // Re-key the open list for the new start (the heuristic changed) and restore the heap.
  for (const std::int32_t n : heap_) {
    Node& node = nodes_[static_cast<std::size_t>(n)];
    node.f = node.g + (target_pos_ - node.pos).norm();
  }
  for (std::size_t i = heap_.size() / 2; i-- > 0;) heapDown(i);
  key_anchor_ = target_pos_;
  return false;
}

void MinimalConstruct::nextStartParent() {
  // repairParent(target_) relaxes the start from every closed node again; a start the
  // obstacles wall in tries hundreds of parents, so that is done once, at its first blocked
  // edge: the candidates (closed nodes it can follow, by g + distance) go into a heap in the
  // order the relaxation picks them (least g, then closing order). closed_ does not change
  // while reattachStart tries them, and each blocked edge removes only its parent, which is
  // the heap's top: the next top is the parent repairParent would find.
  if (!start_candidates_heap_) {
    start_candidates_.clear();
    const Vec2 start = nodes_[kTarget].pos;
    for (std::size_t i = 0; i < closed_.size(); ++i) {
      const std::int32_t c = closed_[i];
      if (!canFollow(c, target_)) continue;
      const Node& a = nodes_[static_cast<std::size_t>(c)];
      start_candidates_.push_back(StartCandidate{a.g + (start - a.pos).norm(), static_cast<std::uint32_t>(i)});
    }
    std::make_heap(start_candidates_.begin(), start_candidates_.end(), StartCandidate::later);
    start_candidates_heap_ = true;
  }
  // The top is the parent just found blocked.
  std::pop_heap(start_candidates_.begin(), start_candidates_.end(), StartCandidate::later);
  start_candidates_.pop_back();
  Node& t = nodes_[kTarget];
  t.state = kUnseen;
  t.parent = kNone;
  t.g = kInf;
  if (start_candidates_.empty()) return;
  const StartCandidate& best = start_candidates_.front();
  t.g = best.g;
  t.f = best.g;  // + |start - start|
  t.parent = closed_[best.closed_index];
  t.state = kOpen;
}

void MinimalConstruct::plantTree(const Vec2& start, const Vec2& goal, bool use_dynamic) {
  resetSearch(goal, use_dynamic);
  target_ = addTargetNode(start);
  Node& root = nodes_[0];
  root.pos = goal;
  root.g = 0.0;
  root.f = (start - goal).norm();
  key_anchor_ = start;
  root.state = kOpen;
  heapPush(0);
  tree_valid_ = true;
  tree_with_dynamic_ = use_dynamic;
  tree_goal_ = goal;
}

std::size_t MinimalConstruct::edgeBlockers(std::int32_t v, bool use_dynamic) {
  const Node& node = nodes_[static_cast<std::size_t>(v)];
  const Node& parent = nodes_[static_cast<std::size_t>(node.parent)];
  const Vec2& u = parent.pos;
  ++edge_checks_;
  // An edge with an end at a static corner touches that obstacle: the oracle is not asked.
  const auto static_vertices = static_cast<std::int32_t>(static_.vertexCount());
  const bool at_static_corner = (node.vertex != kNone && node.vertex < static_vertices) ||
                                (parent.vertex != kNone && parent.vertex < static_vertices);
  // Nor after it failed on an edge the exact test found blocked, until the exact test finds
  // one free: the edges tested one after another are mostly the same way from nearby starts.
  const bool ask = oracle_ != nullptr && !at_static_corner && !oracle_missed_;
  // The root's edges first ask its horizon: the oracle cannot vouch for them when the goal
  // lies on the clearance grid's border (the intermediate goal always does).
  const bool certified = !at_static_corner && node.parent == 0 && rootEdgeCertified(u, node.pos);
  std::size_t nb = certified || (ask && oracle_(oracle_context_, u, node.pos))
                       ? 0
                       : static_.segmentBlockers(u, node.pos, blockers_);
  if (oracle_ != nullptr && !at_static_corner) oracle_missed_ = nb > 0;
  if (use_dynamic) {
    const std::size_t ns_poly = static_.polygonCount();
    const std::size_t nd = dynamic_.segmentBlockers(u, node.pos, std::span<std::uint32_t>(blockers_).subspan(nb));
    for (std::size_t i = nb; i < nb + nd; ++i) blockers_[i] += static_cast<std::uint32_t>(ns_poly);
    nb += nd;
  }
  return nb;
}

bool MinimalConstruct::rootEdgeCertified(const Vec2& u, const Vec2& p) {
  if (!has_region_) return false;
  if (!horizon_.builtFor(u)) {
    if (u != horizon_root_) {
      horizon_root_ = u;
      horizon_tests_ = 0;
    }
    if (++horizon_tests_ < kHorizonAfter) return false;
    horizon_.build(static_, u, region_);
  }
  return horizon_.certifiesFree(p);
}

void MinimalConstruct::blockedEdgeInto(std::int32_t v, std::size_t nb, bool use_dynamic, bool in_heap) {
  markEdgeBlocked(nodes_[static_cast<std::size_t>(v)].parent, v);
  for (std::size_t i = 0; i < nb; ++i) discoverPolygon(blockers_[i], use_dynamic);
  repairParent(v, in_heap);
}

bool MinimalConstruct::edgeIntoFree(std::int32_t v, bool use_dynamic) {
  const std::size_t nb = edgeBlockers(v, use_dynamic);
  if (nb == 0) return true;
  blockedEdgeInto(v, nb, use_dynamic, /*in_heap=*/true);
  return false;
}

void MinimalConstruct::close(std::int32_t v) {
  Node& node = nodes_[static_cast<std::size_t>(v)];
  node.state = kClosed;
  if (node.vertex != kNone && node.parent != kNone) {
    const Vec2& u = nodes_[static_cast<std::size_t>(node.parent)].pos;
    int side = orientSign(u, node.pos, node.prev, orient_bound_);
    if (side == 0) side = orientSign(u, node.pos, node.next, orient_bound_);
    node.turn = static_cast<std::int8_t>(side);
  }
  closed_.push_back(v);
  closed_corner_.push_back(staticCorner(node));
}

MinimalConstruct::Status MinimalConstruct::search(bool use_dynamic, const Deadline& deadline, std::uint32_t until_check,
                                                  Result& result) {
  while (!heap_.empty()) {
    if (until_check-- == 0) {
      // On abort the tree stays valid (closed nodes keep exact distances, the open list is
      // intact; the start is re-attached by the next query), so a later query resumes here.
      if (deadline.passed()) return Status::kAborted;
      until_check = 15;
    }
    const std::int32_t v = heapPop();
    // The lazy step: only now is the edge into v checked against the obstacles.
    if (nodes_[static_cast<std::size_t>(v)].parent != kNone && !edgeIntoFree(v, use_dynamic)) continue;
    close(v);
    ++result.expansions;
    if (v == target_) return Status::kFound;
    expand(v);
  }
  return Status::kNoPath;
}

void MinimalConstruct::tracePath(const Vec2& start_in, const Vec2& goal_in, Result& result) {
  // Parents lead from the start to the goal: the path comes out in driving order.
  if (result.start_moved) path_.push_back(start_in);
  for (std::int32_t n = target_; n != kNone; n = nodes_[static_cast<std::size_t>(n)].parent) {
    path_.push_back(nodes_[static_cast<std::size_t>(n)].pos);
  }
  if (result.goal_moved) path_.push_back(goal_in);
  double length = 0.0;
  for (std::size_t i = 1; i < path_.size(); ++i) length += (path_[i] - path_[i - 1]).norm();
  result.path = path_;
  result.length = length;
}

MinimalConstruct::Result MinimalConstruct::query(const Vec2& start_in, const Vec2& goal_in, bool with_dynamic,
                                                 const Deadline& deadline) {
  Result result;
  path_.clear();
  edge_checks_ = 0;
  const bool use_dynamic = with_dynamic && dynamic_.polygonCount() > 0;

  Vec2 start, goal;
  if (!nearestFreePoint(start_in, use_dynamic, start)) {
    result.status = Status::kStartBlocked;
    return result;
  }
  // Every query of a cycle asks for the same goal among the same obstacles: its free point
  // is kept until the obstacles or the oracle change.
  if (!goal_free_valid_ || !sameBits(goal_in, goal_free_in_) || use_dynamic != goal_free_dynamic_) {
    goal_free_found_ = nearestFreePoint(goal_in, use_dynamic, goal_free_);
    goal_free_in_ = goal_in;
    goal_free_dynamic_ = use_dynamic;
    goal_free_valid_ = true;
  }
  goal = goal_free_;
  if (!goal_free_found_) {
    result.status = Status::kGoalBlocked;
    return result;
  }
  result.start_moved = start != start_in;
  result.goal_moved = goal != goal_in;
  // Every node of this query's graph is a vertex of the two sets, the goal or this start.
  orient_bound_ = orientStaticBound(std::max({static_.maxCoordinate(), dynamic_.maxCoordinate(),
                                              maxAbsCoordinate(start), maxAbsCoordinate(goal)}));

  // The search runs backwards, from the goal (the root, node 0) to the start. Closed nodes
  // then carry exact distances to the goal, which stay true while the goal and the obstacles
  // stay: the next query to the same goal only swaps the start and resumes the search.
  // A kept tree is valid for the same goal and the same obstacles (static, or static plus
  // the dynamic set it was grown with: setDynamicObstacles invalidates it).
  const bool reuse = tree_valid_ && goal == tree_goal_ && use_dynamic == tree_with_dynamic_;
  bool found = false;
  std::uint32_t until_check = 0;  // pops to the search's next deadline check
  if (reuse) {
    found = reattachStart(start, use_dynamic, deadline, until_check, result);
  } else {
    plantTree(start, goal, use_dynamic);
  }
  result.status = found ? Status::kFound : search(use_dynamic, deadline, until_check, result);
  result.edge_checks = edge_checks_;
  result.discovered = total_discovered_;
  if (result.status == Status::kFound) tracePath(start_in, goal_in, result);
  return result;
}

// ---- indexed heap ----

bool MinimalConstruct::heapLess(std::int32_t a, std::int32_t b) const {
  const Node& na = nodes_[static_cast<std::size_t>(a)];
  const Node& nb = nodes_[static_cast<std::size_t>(b)];
  if (na.f != nb.f) return na.f < nb.f;
  if (na.g != nb.g) return na.g > nb.g;
  return a < b;
}

void MinimalConstruct::heapUp(std::size_t i) {
  const std::int32_t n = heap_[i];
  while (i > 0) {
    const std::size_t parent = (i - 1) / 2;
    if (!heapLess(n, heap_[parent])) break;
    heap_[i] = heap_[parent];
    nodes_[static_cast<std::size_t>(heap_[i])].heap_pos = static_cast<std::int32_t>(i);
    i = parent;
  }
  heap_[i] = n;
  nodes_[static_cast<std::size_t>(n)].heap_pos = static_cast<std::int32_t>(i);
}

void MinimalConstruct::heapDown(std::size_t i) {
  const std::int32_t n = heap_[i];
  const std::size_t size = heap_.size();
  for (;;) {
    std::size_t child = 2 * i + 1;
    if (child >= size) break;
    if (child + 1 < size && heapLess(heap_[child + 1], heap_[child])) ++child;
    if (!heapLess(heap_[child], n)) break;
    heap_[i] = heap_[child];
    nodes_[static_cast<std::size_t>(heap_[i])].heap_pos = static_cast<std::int32_t>(i);
    i = child;
  }
  heap_[i] = n;
  nodes_[static_cast<std::size_t>(n)].heap_pos = static_cast<std::int32_t>(i);
}

void MinimalConstruct::heapPush(std::int32_t n) {
  if (n != kTarget) open_scan_valid_ = false;
  heap_.push_back(n);
  heapUp(heap_.size() - 1);
}

void MinimalConstruct::heapDecrease(std::int32_t n) {
  if (n != kTarget) open_scan_valid_ = false;
  heapUp(static_cast<std::size_t>(nodes_[static_cast<std::size_t>(n)].heap_pos));
}

void MinimalConstruct::heapRemove(std::int32_t n) {
  if (n != kTarget) open_scan_valid_ = false;
  const auto i = static_cast<std::size_t>(nodes_[static_cast<std::size_t>(n)].heap_pos);
  const std::int32_t last = heap_.back();
  heap_.pop_back();
  nodes_[static_cast<std::size_t>(n)].heap_pos = kNone;
  if (last == n) return;
  heap_[i] = last;
  nodes_[static_cast<std::size_t>(last)].heap_pos = static_cast<std::int32_t>(i);
  heapUp(i);
  heapDown(static_cast<std::size_t>(nodes_[static_cast<std::size_t>(last)].heap_pos));
}

std::int32_t MinimalConstruct::heapPop() {
  const std::int32_t top = heap_.front();
  if (top != kTarget) open_scan_valid_ = false;
  heap_.front() = heap_.back();
  heap_.pop_back();
  if (!heap_.empty()) heapDown(0);
  nodes_[static_cast<std::size_t>(top)].heap_pos = kNone;
  return top;
}

}  // namespace staa
