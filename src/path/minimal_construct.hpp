#pragma once
// Minimal Construct (Missura, Lee, Bennewitz, IROS 2018): the exact shortest path among
// polygons by A* on a visibility graph that is built lazily.
//
// The search starts with only the start and the goal. Edges are assumed free until the node
// they lead to is popped; only then is the edge checked against the obstacles. When a popped
// edge runs through a polygon, that polygon's convex corners join the graph (connected to
// every closed node), the edge is remembered as blocked, and the node is re-queued through
// its best remaining parent: the search is repaired, not restarted. Edges that cannot be on
// a shortest path are never generated: at a corner, a path must touch the polygon
// tangentially and turn around it. The result is the exact shortest path: ignoring the
// undiscovered polygons can only shorten paths, and the returned path is checked edge by edge
// against all of them.
//
// The search runs backwards from the goal, so its closed nodes hold exact distances to the
// goal. Queries to the same goal among the same obstacles keep the whole search tree: the
// next query (the robot a few centimetres further, or the next state of a STAA* search) only
// connects the new start and resumes. Replacing the dynamic obstacles invalidates a tree
// grown with them; the static polygons discovered for the goal are kept regardless.
//
// Static obstacles (the inflated map M') are indexed once. Dynamic obstacles (the inflated
// moving obstacles D') are replaced every cycle without allocating.
//
// After construction a query allocates nothing, provided the dynamic obstacles stay within
// the capacity given in the options. Not thread-safe: one instance per thread.

#include "path/deadline.hpp"
#include "path/polygon_set.hpp"
#include "path/root_horizon.hpp"
#include "path/tangency_table.hpp"

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace staa {

class MinimalConstruct {
 public:
  struct Options {
    double grid_cell_m = 1.0;                  // edge index cell for the static obstacles
    std::size_t max_dynamic_polygons = 64;     // capacity for D'
    std::size_t max_dynamic_vertices = 4096;
  };

  enum class Status : std::uint8_t {
    kFound,         // path holds the shortest path
    kNoPath,        // start and goal are in different free regions
    kStartBlocked,  // no free point exists near the start (everything is covered)
    kGoalBlocked,   // no free point exists near the goal
    kAborted,       // the deadline passed first; the search tree stays, a later query to
                    // the same goal among the same obstacles resumes it
  };

  struct Result {
    Status status = Status::kNoPath;
    // Polyline from start to goal. When the start or goal lay inside an obstacle, the path
    // runs from/to the nearest free point and the original point is added at that end.
    std::span<const Vec2> path;
    double length = 0.0;  // length of `path`
    bool start_moved = false;
    bool goal_moved = false;
    std::uint32_t expansions = 0;        // nodes closed
    std::uint32_t edge_checks = 0;       // edges checked against the obstacles
    std::uint32_t discovered = 0;        // polygons whose corners are in the graph (incl. kept ones)
  };

  MinimalConstruct() : candidates_(kCandidates) {}
  explicit MinimalConstruct(const Options& options) : options_(options), candidates_(kCandidates) {}

  // Replaces the static obstacles (load time: allocates and sizes every workspace).
  void setStaticObstacles(std::span<const Polygon> polygons);
  // Replaces the dynamic obstacles; no allocation within Options' capacity. Each polygon
  // beyond the capacity is dropped and counted in droppedDynamicPolygons().
  void setDynamicObstacles(std::span<const PolygonView> polygons);
  void clearDynamicObstacles();
  // Forgets the search tree and the polygons kept for the last goal: the next query starts
  // as on a new instance (a replay from that point then repeats the same work).
  void forgetGoal() {
    tree_valid_ = false;
    have_goal_ = false;
  }

  const PolygonSet& staticObstacles() const { return static_; }
  const PolygonSet& dynamicObstacles() const { return dynamic_; }
  std::size_t droppedDynamicPolygons() const { return dropped_dynamic_; }

  // An optional quick test that may declare a segment free of the static obstacles (true
  // only when it certainly is, e.g. from a clearance map); anything else falls back to the
  // exact test. Plain function pointer and context: no allocation, no virtual call. It is
  // not asked about an edge with an end at a static corner (the edge touches that obstacle,
  // which no clearance vouches for), nor after the exact test found the last edge it could
  // have been asked about blocked (until one is found free): it only saves work, the answer
  // is the exact test's either way.
  using FreeSegmentOracle = bool (*)(const void* context, const Vec2& a, const Vec2& b);
  void setFreeSegmentOracle(FreeSegmentOracle oracle, const void* context) {
    oracle_ = oracle;
    oracle_context_ = context;
    goal_free_valid_ = false;
  }

  // Shortest path from start to goal among the static obstacles, plus the dynamic ones when
  // `with_dynamic`. The returned span stays valid until the next query. The deadline is
  // checked every 16 expansions (a few microseconds apart).
  Result query(const Vec2& start, const Vec2& goal, bool with_dynamic, const Deadline& deadline = {});
  // The static corners' pairwise tangency is precomputed by setStaticObstacles (TangencyTable,
  // shared between searches over the same obstacles): the same answers, faster expansions.
  // Off (for the next setStaticObstacles): every expansion tests every node, as a reference.
  void setTangencyTable(bool on) { use_tangency_table_ = on; }
  // Where the next queries' starts lie (the heuristic's: the local box, grown). The edges from
  // the root (the goal) to starts in it first ask a table of the root's free directions
  // (path/root_horizon.hpp), built once the root's edges have been tested kHorizonAfter times:
  // for a tree asked from many nearby starts.
  void setStartRegion(const Box& region) {
    if (has_region_ && region.min == region_.min && region.max == region_.max) return;
    region_ = region;
    has_region_ = true;
    horizon_.clear();
    horizon_tests_ = 0;
  }

  // Is a point free (outside every obstacle's interior) / is a segment free?
  bool pointFree(const Vec2& p, bool with_dynamic) const;
  bool segmentFree(const Vec2& a, const Vec2& b, bool with_dynamic) const;
  // The free point nearest to p among both obstacle sets; false if there is none.
  bool nearestFreePoint(const Vec2& p, bool with_dynamic, Vec2& out) const;

 private:
  static constexpr std::int32_t kNone = -1;
  static constexpr std::int32_t kTarget = 1;  // node id of the start (the backward search's target)
  static constexpr std::size_t kCandidates = 256;
  enum : std::uint8_t { kUnseen = 0, kOpen = 1, kClosed = 2 };

  struct Node {
    Vec2 pos{0.0, 0.0};
    // The corner's neighbours on its polygon (for the tangency tests), copied in so that the
    // inner loop of the search touches one array only.
    Vec2 prev{0.0, 0.0};
    Vec2 next{0.0, 0.0};
    // Global vertex id: static vertices first, then dynamic ones; kNone for start/goal.
    std::int32_t vertex = kNone;
    std::int32_t parent = kNone;
    double g = 0.0;
    double f = 0.0;
    std::int32_t heap_pos = kNone;
    std::uint8_t state = kUnseen;
    // Set when closed: the side (+1 left, -1 right) the polygon lies on, seen along the edge
    // from the parent; successors must turn that way. 0: no constraint.
    std::int8_t turn = 0;
  };


  void resetSearch(const Vec2& goal, bool with_dynamic);
  std::int32_t addTargetNode(const Vec2& start);
  // Adds the polygon's free convex corners to the graph and connects them; polygons that
  // cover one of its corners are discovered with it (they shape the free space there).
  void discoverPolygon(std::uint32_t global_polygon, bool with_dynamic);
  void discoverOne(std::uint32_t global_polygon, bool with_dynamic);
  bool markDiscovered(std::uint32_t global_polygon);  // false when it already was
  bool canFollow(std::int32_t from, std::int32_t to) const;
  // The way through `from` to `to` if it is shorter and allowed: g, f and parent set (true).
  bool improve(std::int32_t from, std::int32_t to);
  void relax(std::int32_t from, std::int32_t to);
  // relax for a node that is not closed and not in the heap (reattachStart's start): its
  // g, f and parent, no heap operation.
  void relaxOutsideHeap(std::int32_t from, std::int32_t to);
  void expand(std::int32_t v);
  // The node's parent found again among the closed nodes; `in_heap` false keeps it out of the
  // heap (reattachStart's start, pushed only when the search needs it).
  void repairParent(std::int32_t node, bool in_heap);
  // relax(c, node) for every closed c in closing order (relaxOutsideHeap when !in_heap); with
  // the table, closed corners outside a static corner's row are skipped (canFollow's answer).
  void relaxFromClosed(std::int32_t node, bool in_heap);
  // query()'s steps: a kept tree takes the new start (true when the start is found at once,
  // without a search), or a new tree is planted at the goal; the search pops until the start
  // is closed, the heap is empty or the deadline passes; the path is traced from the start.
  // A kept tree's start connected by reattachStart may be its next pop (its edge free:
  // found; blocked: the search's step for a blocked edge is taken without a search) or not.
  enum class StartStep : std::uint8_t { kFound, kBlocked, kNotNext };
  bool reattachStart(const Vec2& start, bool use_dynamic, const Deadline& deadline, std::uint32_t& until_check,
                     Result& result);
  StartStep startIsNextPop(bool use_dynamic, Result& result);
  // reattachStart's repairParent(target_) after a blocked edge into the start, from a heap of
  // candidates built at the first one.
  void nextStartParent();
  void plantTree(const Vec2& start, const Vec2& goal, bool use_dynamic);
  // `until_check`: pops before the first deadline check (0: at once).
  Status search(bool use_dynamic, const Deadline& deadline, std::uint32_t until_check, Result& result);
  // The lazy edge check into a popped node; a blocked edge discovers its blockers and repairs
  // the node's parent (false).
  bool edgeIntoFree(std::int32_t v, bool use_dynamic);
  // The polygons the edge into v (from its parent) runs through, into blockers_ (0: free).
  std::size_t edgeBlockers(std::int32_t v, bool use_dynamic);
  // The step for a blocked edge into v: the edge remembered, its blockers discovered, v
  // re-parented (`in_heap` as repairParent's).
  void blockedEdgeInto(std::int32_t v, std::size_t blockers, bool use_dynamic, bool in_heap);
  void close(std::int32_t v);
  void tracePath(const Vec2& start_in, const Vec2& goal_in, Result& result);
  bool edgeKnownBlocked(std::int32_t a, std::int32_t b) const;
  void markEdgeBlocked(std::int32_t a, std::int32_t b);

  // Indexed binary min-heap on f (ties: larger g first), over node ids.
  void heapPush(std::int32_t n);
  void heapDecrease(std::int32_t n);
  std::int32_t heapPop();
  void heapRemove(std::int32_t n);
  void heapUp(std::size_t i);
  void heapDown(std::size_t i);
  bool heapLess(std::int32_t a, std::int32_t b) const;

  Options options_;
  FreeSegmentOracle oracle_ = nullptr;
  const void* oracle_context_ = nullptr;
  bool oracle_missed_ = false;  // the last edge the oracle was asked about (or skipped) was blocked
  bool staticFree(const Vec2& a, const Vec2& b) const {
    return (oracle_ != nullptr && oracle_(oracle_context_, a, b)) || !static_.segmentBlocked(a, b);
  }
  struct Candidate {
    Vec2 point{0.0, 0.0};
    Vec2 edge{1.0, 0.0};
    double distance = 0.0;
  };
  // nearestFreePoint's candidate boundary points, nearest first.
  mutable std::vector<Candidate> candidates_;
  PolygonSet static_;
  PolygonSet dynamic_;
  std::size_t dropped_dynamic_ = 0;

  // Search workspace, sized at setStaticObstacles / by the dynamic capacity.
  std::vector<Node> nodes_;
  // The static corners' pairwise tangency (null without one: too many corners). With it an
  // expansion of a static corner visits the corners its row lists (corner_node_: each
  // corner's node in this search, or kNone) and the other nodes (other_nodes_: dynamic
  // corners; the goal and the start, nodes 0 and 1, are always visited).
  bool use_tangency_table_ = true;
  RootHorizon horizon_;
  Box region_;
  bool has_region_ = false;
  Vec2 horizon_root_{0.0, 0.0};        // the root whose edges horizon_tests_ counts
  std::uint32_t horizon_tests_ = 0;
  static constexpr std::uint32_t kHorizonAfter = 32;
  // True when the horizon vouches that the static obstacles leave the edge from the root at u
  // to p free (builds the table once the root's edges are asked about often enough).
  bool rootEdgeCertified(const Vec2& u, const Vec2& p);
  std::shared_ptr<const TangencyTable> tangency_;
  std::vector<std::int32_t> corner_node_;
  std::vector<std::int32_t> other_nodes_;
  // The static corner index of a node (-1: none, or no table).
  std::int32_t staticCorner(const Node& n) const {
    return tangency_ && n.vertex != kNone && static_cast<std::size_t>(n.vertex) < static_.vertexCount()
               ? tangency_->cornerOf(static_cast<std::size_t>(n.vertex))
               : -1;
  }
  std::vector<std::int32_t> heap_;
  std::vector<std::int32_t> closed_;             // closed node ids in closing order
  std::vector<std::int32_t> closed_corner_;      // their static corner indices (-1: none)
  // startIsNextPop's scan: the open nodes but the start (position, g), valid until the heap's
  // other nodes or their g change.
  struct ScanEntry {
    Vec2 pos{0.0, 0.0};
    double g = 0.0;
  };
  std::vector<ScanEntry> open_scan_;
  bool open_scan_valid_ = false;
  std::vector<std::uint8_t> static_discovered_;  // persists across queries to the same goal
  std::vector<std::uint8_t> dynamic_discovered_;
  std::vector<std::uint32_t> blockers_;
  std::size_t start_blockers_ = 0;  // startIsNextPop's count in blockers_ (kBlocked)
  std::vector<std::uint32_t> pending_;   // polygons waiting to be discovered
  std::vector<std::uint32_t> rediscover_;  // kept polygons, while a new graph is started
  std::vector<std::uint32_t> covering_;
  mutable bool overflow_ = false;
  // Per static vertex: the other static polygons that contain it (CSR), computed once.
  std::vector<std::uint32_t> static_cover_offsets_;
  std::vector<std::uint32_t> static_cover_;
  std::vector<Vec2> path_;
  std::vector<std::int32_t> target_blocked_;  // nodes whose edge to the current start is blocked
  // reattachStart's parents for the start: closed nodes it can follow, by g + distance.
  struct StartCandidate {
    double g = 0.0;
    std::uint32_t closed_index = 0;
    // The heap's order: least g first, then the earlier closed node (relax keeps the first).
    static bool later(const StartCandidate& a, const StartCandidate& b) {
      return a.g > b.g || (a.g == b.g && a.closed_index > b.closed_index);
    }
  };
  std::vector<StartCandidate> start_candidates_;
  bool start_candidates_heap_ = false;
  // Open-addressing set of blocked (node, node) edges, cleared in O(1) by a generation stamp.
  std::vector<std::uint64_t> blocked_keys_;
  std::vector<std::uint32_t> blocked_gen_;
  std::uint32_t blocked_generation_ = 1;
  std::size_t blocked_count_ = 0;

  // The last goal's nearest free point (query), valid until the obstacles or the oracle change.
  Vec2 goal_free_in_{0.0, 0.0};
  Vec2 goal_free_{0.0, 0.0};
  bool goal_free_found_ = false;
  bool goal_free_dynamic_ = false;
  bool goal_free_valid_ = false;
  Vec2 goal_pos_{0.0, 0.0};   // the goal whose discovered polygons are kept
  bool have_goal_ = false;
  Vec2 target_pos_{0.0, 0.0};  // the start: the backward search's target, its heuristic's anchor
  Vec2 key_anchor_{0.0, 0.0};  // the start the heap's keys were last computed for
  double orient_bound_ = 0.0;  // orientStaticBound for the points of the current query
  std::int32_t target_ = kNone;
  bool tree_valid_ = false;    // the search tree may be resumed for tree_goal_
  bool tree_with_dynamic_ = false;  // ... and it was grown with the dynamic obstacles
  Vec2 tree_goal_{0.0, 0.0};
  std::uint32_t total_discovered_ = 0;
  std::uint32_t edge_checks_ = 0;
};

}  // namespace staa
