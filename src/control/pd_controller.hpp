#pragma once
// The paper's simplest baseline (Sec. IV-B): a PD controller that follows a "carrot" on the
// global path, with a force field that pushes the robot away from obstacles that come too
// close (static ones from the collision grid C, moving ones from D predicted a short time
// ahead). No planning: one command from the current state, every cycle.
//
// The authors' PD produced accelerations (a, b); here they are integrated over one control
// period into the velocity command, v_cmd = v + a * period, w_cmd = w + b * period, with
// |a| <= a_max and |b| <= b_max, so the command is always one the robot can follow.

#include "control/local_controller.hpp"
#include "robot/robot_profile.hpp"

#include <array>
#include <vector>

namespace staa {

// Defaults are the tuned values. The carrot offset and the four gains are the authors'
// published configuration (their PD gave accelerations; here integrated over one period, see
// above); the sweeps kept them (0.4 m was slower, 1.0 m and more gave 3-4 collisions).
// The rest was tuned on the seven scenarios of
// tests/unit/control/scenarios.hpp with PdTuning in test_pd_controller.cpp: each parameter
// swept over 4-6 values around the current best, one at a time, scored by goals reached,
// then fewest collision episodes, then least total time; two rounds. Decisive: predicting
// the robot too (ff_predict_s 0 -> 1 s: 3 -> 1 collisions) and ff_gain_lin >= 12 (below,
// the PD's pull of 10 * 0.6 m/s^2 outweighs the push); the vortex angle saved 3 s in the
// corridor (0.6 and more added collisions or lost a goal); ties in collisions went to the
// larger ranges (clearance) over small time gains. With these values: 7/7 goals, one
// collision (the person walking head-on in the 2 m corridor), 57.4 s in total.
struct PdConfig {
  // The carrot: this far along the global path from the robot's closest point on it.
  double carrot_offset_m = 0.6;
  // The authors' PD, on accelerations:
  //   a = kp_lin * |carrot - robot| + kd_lin * v,   b = kp_rot * heading_error + kd_rot * w.
  double kp_lin = 10.0;
  double kd_lin = -1.0;
  double kp_rot = 70.0;
  double kd_rot = -15.0;
  // Forward speed falls linearly with the heading error to the carrot and is zero (turn on
  // the spot) at this error and beyond.
  double heading_stop_rad = 1.2;
  // Goal slow-down: v <= sqrt(2 * goal_decel * remaining path length), so the robot arrives
  // (nearly) standing; inside goal_align_radius it stops and turns to the goal's heading
  // (the cycle declares arrival within 0.2 m, 0.4 rad and 0.25 m/s).
  double goal_decel = 1.5;          // m/s^2, below a_max: margin for the discrete steps
  double goal_align_radius_m = 0.12;
  // Force field. Each obstacle within range pushes with magnitude ((range - d) / range)^2
  // (d: clearance to the footprint), along the shortest line from it to the footprint.
  // Static obstacles: the nearest occupied cell of C in each of kSectors bearings.
  double ff_static_range_m = 0.5;
  // Moving obstacles: their positions now and predicted up to ff_predict_s ahead (at
  // ff_predict_steps + 1 times, constant velocity), measured from the robot predicted the
  // same time ahead at its current (v, w); the strongest push of each.
  double ff_dynamic_range_m = 1.2;
  double ff_predict_s = 1.0;
  int ff_predict_steps = 4;
  // The moving obstacles' push turned counter-clockwise by this angle (a vortex field): a
  // head-on push then also turns the robot to its right, where a symmetric field would only
  // brake. 0: a plain repulsive field.
  double ff_vortex_rad = 0.4;
  // The push in the robot frame: its backward part brakes (acceleration), its sideways part
  // turns away (angular acceleration, in the direction of travel).
  double ff_gain_lin = 12.0;   // m/s^2 per unit push
  double ff_gain_rot = 30.0;   // rad/s^2 per unit push
  // Backward driving: only the force field may push the robot back, at most this fast.
  double ff_max_reverse = 0.5;  // m/s
};

class PdController final : public LocalController {
 public:
  static constexpr int kSectors = 16;

  explicit PdController(const RobotProfile& robot, const PdConfig& config = {});

  const char* name() const override { return "pd"; }
  LocalCommand compute(const LocalContext& context) override;

  const PdConfig& config() const { return config_; }

  // The parts of the last command (tests, drawing).
  struct Terms {
    Vec2 carrot{0.0, 0.0};        // world
    double heading_error = 0.0;   // rad, to the carrot (or the goal's heading when aligning)
    double remaining_m = 0.0;     // along the path to the goal
    Vec2 force{0.0, 0.0};         // robot frame, static + dynamic push
    bool aligning = false;        // at the goal: turning to its heading
  };
  const Terms& terms() const { return terms_; }

 private:
  // The carrot and the path length from the robot's closest point to the path's end.
  void findCarrot(const LocalContext& ctx, Vec2& carrot, double& remaining) const;
  // The push of the occupied cells of C near the robot (robot frame).
  Vec2 staticForce(const LocalContext& ctx) const;
  // The push of the moving obstacles, now and predicted (robot frame).
  Vec2 dynamicForce(const LocalContext& ctx);

  RobotProfile robot_;
  PdConfig config_;
  double reach_ = 0.0;  // the footprint's circumradius
  std::vector<Vec2> footprint_world_;  // scratch, sized at construction
  FixedPolygon predicted_;             // scratch for D(t)
  Terms terms_;
};

}  // namespace staa
