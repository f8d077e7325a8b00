// rounded_path.h: a closed horizontal path through waypoints whose corners are circular arcs,
// parameterised by arc length (the simulator's lawnmower and wreck-circling trajectories).
// Position and unit tangent are continuous everywhere (curvature jumps where a line meets an arc).
// Units: metres. Frame: world x, y (the path is planar; callers choose its height).
// Threads: immutable after construction.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace cenote::sim {

class RoundedPath {
 public:
  // @param waypoints corners of a closed polygon (>= 3, consecutive points distinct)
  // @param radius_m  corner radius; every edge must be at least 2 * radius_m * tan(turn / 2) long
  // @throws cenote::Error when the corners do not fit.
  RoundedPath(const std::vector<Eigen::Vector2d>& waypoints, double radius_m);

  double length_m() const { return length_m_; }
  // Point at arc length s (taken modulo the length, so any s is valid).
  Eigen::Vector2d position(double s_m) const;
  // Unit direction of travel at arc length s.
  Eigen::Vector2d tangent(double s_m) const;

 private:
  struct Segment {
    double start_s = 0.0, length = 0.0;
    bool arc = false;
    Eigen::Vector2d a = Eigen::Vector2d::Zero(), direction = Eigen::Vector2d::Zero();  // line: start, unit dir
    Eigen::Vector2d center = Eigen::Vector2d::Zero();                                  // arc
    double radius = 0.0, start_angle = 0.0, sweep = 0.0;                               // arc, signed sweep
  };
  const Segment& find(double& s_m) const;

  std::vector<Segment> segments_;
  double length_m_ = 0.0;
};

}  // namespace cenote::sim
