#pragma once
// The scenarios the STAA* issue demands, built in code on real geometry: open space, a door
// with a 90-degree turn, a goal behind the robot, a U-shaped trap facing the start, a person
// walking towards the robot in a 2 m corridor, a mover crossing at right angles, and a gap
// that closes in front of the robot and opens again.

#include "robot/robot_profile.hpp"
#include "world/scenario.hpp"

#include <string>

namespace staa::test {

inline Polygon box(double x0, double y0, double x1, double y1) { return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}; }

inline Scenario baseScenario(const std::string& name, Box bounds) {
  Scenario s;
  s.name = name;
  s.map.name = name;
  s.map.bounds = bounds;
  s.robot = paperAgentProfile();
  return s;
}

inline Scenario openSpace() {
  Scenario s = baseScenario("open", Box{{0, 0}, {16, 16}});
  s.start = {2, 2, 0.0};
  s.goal = {13, 11, 1.57};
  return s;
}

// Two rooms joined by a 1.35 m door in the wall x = 6; the goal is around the corner, so the
// robot must pass the door and turn by 90 degrees.
inline Scenario doorTurn() {
  Scenario s = baseScenario("door", Box{{0, 0}, {12, 8}});
  s.map.obstacles = {box(5.94, 0, 6.06, 2.0), box(5.94, 3.35, 6.06, 8)};  // door y in [2.0, 3.35]
  s.start = {2, 2.7, 0.0};
  s.goal = {8.5, 6.5, 1.5708};
  return s;
}

// The goal lies 2 m behind the robot.
inline Scenario goalBehind() {
  Scenario s = baseScenario("behind", Box{{0, 0}, {12, 8}});
  s.start = {6, 4, 0.0};
  s.goal = {4, 4, 0.0};
  return s;
}

// A U whose pocket opens towards the start: the straight line to the goal runs into its
// floor; the way is around an arm.
inline Scenario uTrap() {
  Scenario s = baseScenario("u-trap", Box{{0, 0}, {16, 12}});
  s.map.obstacles = {box(7.0, 3.0, 7.3, 9.0), box(4.0, 3.0, 7.3, 3.3), box(4.0, 8.7, 7.3, 9.0)};
  s.start = {2, 6, 0.0};
  s.goal = {12, 6, 0.0};
  return s;
}

// A 2 m wide corridor, 20 m long; a person (0.5 m square) walks towards the robot along it.
inline Scenario corridorPerson() {
  Scenario s = baseScenario("corridor", Box{{0, 0}, {22, 2}});
  s.start = {1.0, 1.0, 0.0};
  s.goal = {20.5, 1.0, 0.0};
  Mover person;
  person.polygon = box(-0.25, -0.25, 0.25, 0.25);
  person.waypoints = {{19.0, 1.0}, {1.5, 1.0}};
  person.speed = 1.0;
  s.movers.push_back(person);
  return s;
}

// A mover crosses the robot's straight path at right angles, timed to meet it.
inline Scenario crossing() {
  Scenario s = baseScenario("crossing", Box{{0, 0}, {16, 10}});
  s.start = {1.0, 5.0, 0.0};
  s.goal = {14.0, 5.0, 0.0};
  Mover m;
  m.polygon = box(-0.3, -0.3, 0.3, 0.3);
  m.waypoints = {{7.5, 0.5}, {7.5, 9.5}};
  m.speed = 1.2;
  s.movers.push_back(m);
  return s;
}

// A 1.6 m gap in a wall; two sliding doors (movers) close it while the robot approaches
// (shut 3 s after the start, when the robot is about to arrive) and open it again 3 s later.
// The robot must brake in front of the gap, wait, and then pass.
inline Scenario closingGap() {
  Scenario s = baseScenario("closing-gap", Box{{0, 0}, {14, 8}});
  s.map.obstacles = {box(7.0, 0, 7.2, 3.2), box(7.0, 4.8, 7.2, 8)};  // gap y in [3.2, 4.8]
  s.start = {2.0, 4.0, 0.0};
  s.goal = {12.0, 4.0, 0.0};
  Mover lower, upper;
  lower.polygon = box(-0.1, -0.8, 0.1, 0.8);
  lower.waypoints = {{7.1, 2.4}, {7.1, 3.6}};  // open (flush with the wall) .. closed
  lower.speed = 0.4;
  upper.polygon = box(-0.1, -0.8, 0.1, 0.8);
  upper.waypoints = {{7.1, 5.6}, {7.1, 4.4}};
  upper.speed = 0.4;
  s.movers = {lower, upper};
  return s;
}

// ---- Passages narrower than the circumscribed circle (issue 16) ----

// A rectangular base, `length` x `width`, its origin at the centre (a typical AMR).
inline RobotProfile rectangleRobot(double length, double width) {
  RobotProfile r;
  r.name = "rectangle";
  const double x = 0.5 * length, y = 0.5 * width;
  r.footprint = {{x, -y}, {x, y}, {-x, y}, {-x, -y}};  // counter-clockwise
  r.limits = MotionLimits{1.0, -0.5, 2.0, 1.0, 3.0};
  return r;
}

// A 0.2 m thick wall across a 12 x 8 m room with one slot of `width` (centred at y = 4); a
// 0.5 x 0.8 m robot goes from one side to the other.
inline Scenario slot(double width) {
  Scenario s = baseScenario("slot", Box{{0, 0}, {12, 8}});
  s.robot = rectangleRobot(0.8, 0.5);
  s.map.obstacles = {box(5.9, 0, 6.1, 4.0 - 0.5 * width), box(5.9, 4.0 + 0.5 * width, 6.1, 8)};
  s.start = {2.0, 4.0, 0.0};
  s.goal = {10.0, 4.0, 0.0};
  return s;
}

// The same slot in a wall at 45 degrees: the wall runs along x + y = 12 through (6, 6).
inline Scenario slotAt45(double width) {
  Scenario s = baseScenario("slot-45", Box{{0, 0}, {12, 12}});
  s.robot = rectangleRobot(0.8, 0.5);
  const Vec2 c{6.0, 6.0};
  const Vec2 along = Vec2(-1.0, 1.0).normalized(), across = Vec2(1.0, 1.0).normalized();
  auto piece = [&](double s0, double s1) {  // the wall from s0 to s1 along it, 0.2 m thick
    return Polygon{c + s0 * along - 0.1 * across, c + s1 * along - 0.1 * across, c + s1 * along + 0.1 * across,
                   c + s0 * along + 0.1 * across};
  };
  s.map.obstacles = {piece(0.5 * width, 9.0), piece(-9.0, -0.5 * width)};
  s.start = {3.0, 3.0, 0.0};
  s.goal = {9.0, 9.0, 0.7854};
  return s;
}

// A 0.7 m door in the wall x = 6 opens into a 1.1 m corridor that runs north at once: the
// robot passes the door and turns by 90 degrees behind it.
inline Scenario doorThenTurn() {
  Scenario s = baseScenario("door-turn", Box{{0, 0}, {10, 8}});
  s.robot = rectangleRobot(0.8, 0.5);
  s.map.obstacles = {box(5.9, 0, 6.1, 1.65), box(5.9, 2.35, 6.1, 8),  // the door: y in [1.65, 2.35]
                     box(7.2, 0, 7.4, 8)};                             // the corridor: x in [6.1, 7.2]
  s.start = {3.0, 2.0, 0.0};
  s.goal = {6.65, 6.5, 1.5708};
  return s;
}

// The building: four 4 m rooms in a row, 1.2 m doors, furniture near each door that
// leaves 0.75-0.8 m to pass, and a 0.5 m wide, 0.65 m long robot whose goal is three rooms away.
inline Scenario buildingOfFourRooms() {
  Scenario s = baseScenario("building", Box{{0, 0}, {16, 4}});
  s.robot = rectangleRobot(0.65, 0.5);
  for (double x : {4.0, 8.0, 12.0}) {  // walls with a door at y in [1.4, 2.6]
    s.map.obstacles.push_back(box(x - 0.05, 0.0, x + 0.05, 1.4));
    s.map.obstacles.push_back(box(x - 0.05, 2.6, x + 0.05, 4.0));
  }
  s.map.obstacles.push_back(box(3.45, 2.15, 3.95, 2.65));  // a cabinet beside the first door: 0.75 m left
  s.map.obstacles.push_back(box(8.1, 0.9, 8.6, 1.4 + 0.45)); // a chair behind the second: 0.75 m
  s.map.obstacles.push_back(box(11.4, 2.2, 11.9, 3.0));      // shelves in front of the third: 0.8 m
  s.map.obstacles.push_back(box(0.5, 0.3, 1.5, 1.0));        // a table in the first room
  s.start = {1.5, 2.0, 0.0};
  s.goal = {14.5, 2.0, 0.0};
  return s;
}

}  // namespace staa::test
