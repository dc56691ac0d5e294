#pragma once
// A simulated depth camera (docs/ARCHITECTURE.md section 4, `sim`): renders DepthFrames by ray
// casting from the camera (robot pose + mount) into the polygon map, so perception runs on
// real frames in tests and in the simulator. The world is vertical prisms: the map's
// obstacles and its bounds from the floor to wall_height_m, movers to mover_height_m, and
// optionally the floor. Each pixel's depth is the optical z of the first surface its ray
// meets (what OpenNI's PIXEL_FORMAT_DEPTH_1_MM reports), 0 for no reading.
//
// Speed: rays are binned by azimuth; per frame only edges within max_depth_m are binned,
// nearest first, so a pixel tests the few edges in its direction and stops at the first one
// farther than what it already hit. Everything is sized at construction except the bins'
// item list, which grows only on a frame that needs more than any before.

#include "geometry/splitmix64.hpp"
#include "geometry/types.hpp"
#include "hal/depth_camera.hpp"
#include "map/polygon_map.hpp"
#include "hal/camera_model.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace staa {
class World;
}

namespace staa::hal {

struct SimDepthConfig {
  CameraIntrinsics intrinsics;
  CameraMount mount;             // the camera on the robot (default 1 m up, level)
  double wall_height_m = 2.0;    // the map's obstacles and bounds: prisms this tall
  double mover_height_m = 1.7;   // movers (people) in SimDepthCamera
  bool floor = true;             // the floor returns depth, as it does for a real camera
  double min_depth_m = 0.45;     // nearer surfaces give no reading (0), as on the Xtion
  double max_depth_m = 8.0;      // farther ones too
  // Depth noise: Gaussian with standard deviation noise_mm_per_m2 * depth^2 (depth in m).
  // Kinect-class sensors: a few mm at 0.5 m to ~4 cm at 5 m (Khoshelham & Oude Elberink
  // 2012), about 1.5 mm/m^2. 0: exact depths (rounded to mm).
  double noise_mm_per_m2 = 0.0;
  // Dropouts: this fraction of the pixels gives no reading at random, and so does every
  // surface seen more than grazing_deg off its normal (the projected pattern does not come
  // back). 0 and 90: none.
  double dropout = 0.0;
  double grazing_deg = 90.0;
  std::uint64_t seed = 1;        // of the noise and the dropouts
  int pixel_stride = 1;          // render every n-th pixel of every n-th row (others 0)
  double rate_hz = 30.0;         // SimDepthCamera's frame rate
};

// A prism besides the map's: a polygon about its origin placed at `position`, from the floor
// up to height_m. The view must stay valid during render().
struct PrismView {
  PolygonView shape;
  Vec2 position{0.0, 0.0};
  double height_m = 1.7;
};

// The map's obstacles and its bounds as the simulated sensors see them: every polygon's
// points in one array, each with its bounding box (to skip what is out of range) and whether
// it is solid (the bounds are a box seen from inside, with no top).
struct StaticPrisms {
  struct Entry {
    std::uint32_t first = 0, count = 0;  // in points
    Box box;                             // map frame
    bool solid = true;
  };
  explicit StaticPrisms(const PolygonMap& map);
  std::span<const Vec2> pointsOf(const Entry& e) const { return {points.data() + e.first, e.count}; }
  std::vector<Vec2> points;
  std::vector<Entry> entries;
};

class DepthRenderer {
 public:
  static constexpr std::size_t kMaxMoverEdges = 1024;   // movers' edges per frame (the rest unseen)
  static constexpr std::size_t kMaxMoverVertices = 64;  // per mover (a larger one is unseen)
  static constexpr int kBins = 512;                    // azimuth bins over the field of view

  // Throws std::invalid_argument naming the field for a bad camera or config value.
  DepthRenderer(const PolygonMap& map, const SimDepthConfig& config);

  // The frame seen from a robot at `robot` (map frame) among `movers`. Sets depth_mm only
  // (the caller stamps it). `mover_pixels` (empty, or one per mover): how many rendered
  // pixels show each mover (a reading whose nearest surface is that mover's).
  void render(const Pose2& robot, std::span<const PrismView> movers, DepthFrame& out,
              std::span<std::uint32_t> mover_pixels = {});

  const CameraModel& camera() const { return camera_; }
  const SimDepthConfig& config() const { return config_; }

 private:
  struct PixelRay {  // the pixel's ray in the base frame, optical z = 1
    float x, y, z;
    float inv_horizontal;  // 1 / its horizontal length (0: it can only meet the floor)
    float inv_norm;        // 1 / its length
    std::uint16_t bin;
  };
  struct Edge {  // camera-relative, base-aligned (the robot's heading removed)
    Vec2 p{0.0, 0.0};
    Vec2 e{0.0, 0.0};
    double height = 0.0;
    double near = 0.0;               // its horizontal distance from the camera
    double inv_length = 0.0;         // 1 / |e| (0 for a degenerate edge)
    std::uint32_t prism = 0;         // the prism it bounds
    int bins[4] = {-1, -1, -1, -1};  // up to two inclusive bin ranges
  };
  struct Prism {  // a polygon of edges_[first, first + count)
    std::uint32_t first = 0, count = 0;
    double height = 0.0;
    Box box;  // camera-relative
  };
  void addPrism(std::span<const Vec2> points_map, double height, bool solid, const Vec2& camera, double c, double s);
  void binEdge(Edge& edge) const;
  int binOf(double relative_azimuth) const;

  SimDepthConfig config_;
  CameraModel camera_;
  double yaw0_ = 0.0;                  // azimuths are measured from the camera's yaw
  double fov_min_ = 0.0, bin_width_ = 1.0;
  std::vector<PixelRay> rays_;         // per pixel (all 640 x 480; unrendered ones unused)
  StaticPrisms static_;
  // Per frame.
  std::vector<Edge> edges_;
  std::vector<Prism> prisms_;
  std::vector<std::uint32_t> low_prisms_;  // lower than the camera: their tops can be seen
  std::vector<std::uint32_t> prism_mover_;  // per prism: its mover's index, or kNoMover
  static constexpr std::uint32_t kNoMover = 0xFFFFFFFFu;
  std::array<std::uint32_t, kBins + 1> bin_start_{};
  std::vector<std::uint32_t> bin_items_;
  SplitMix64 rng_;
};

// A DepthCamera over a simulator World: read() renders the world as it is (robot pose and
// movers, each mover a prism of mover_height_m) on a fixed schedule of rate_hz. Reads the
// World directly: call it on the thread that steps the world (tests, lockstep simulation).
class SimDepthCamera final : public DepthCamera {
 public:
  SimDepthCamera(const World& world, const SimDepthConfig& config);

  // A new frame, stamped `now`, when one is due (30 Hz: at most one per 33 ms, on a fixed
  // schedule; a late poll does not make a burst). Allocation-free after the first frames.
  bool read(rt::Nanos now, DepthFrame& out) override;
  CameraIntrinsics intrinsics() const override { return renderer_.config().intrinsics; }
  CameraMount mount() const override { return renderer_.config().mount; }

 private:
  const World& world_;
  DepthRenderer renderer_;
  std::vector<PrismView> movers_;
  rt::Nanos period_;
  rt::Nanos next_due_ = -1;
  std::uint64_t sequence_ = 0;
};

}  // namespace staa::hal
