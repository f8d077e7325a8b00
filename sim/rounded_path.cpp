#include "sim/rounded_path.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.h"

namespace cenote::sim {

RoundedPath::RoundedPath(const std::vector<Eigen::Vector2d>& w, double radius_m) {
  const size_t n = w.size();
  if (n < 3) throw Error("RoundedPath: needs at least 3 waypoints");
  // Per corner: entry point, exit point, arc.
  std::vector<Eigen::Vector2d> entry(n), exit(n);
  std::vector<Segment> arcs(n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d in = w[i] - w[(i + n - 1) % n], out = w[(i + 1) % n] - w[i];
    if (in.norm() < 1e-9 || out.norm() < 1e-9) throw Error("RoundedPath: repeated waypoint " + std::to_string(i));
    const Eigen::Vector2d a = in.normalized(), b = out.normalized();
    const double cross = a.x() * b.y() - a.y() * b.x();
    const double turn = std::atan2(cross, a.dot(b));  // signed, left positive
    const double cut = radius_m * std::tan(std::abs(turn) / 2.0);
    entry[i] = w[i] - a * cut;
    exit[i] = w[i] + b * cut;
    Segment& arc = arcs[i];
    arc.arc = true;
    arc.radius = radius_m;
    arc.sweep = turn;
    const Eigen::Vector2d left(-a.y(), a.x());
    arc.center = entry[i] + (turn >= 0 ? 1.0 : -1.0) * left * radius_m;
    const Eigen::Vector2d r0 = entry[i] - arc.center;
    arc.start_angle = std::atan2(r0.y(), r0.x());
    arc.length = radius_m * std::abs(turn);
  }
  for (size_t i = 0; i < n; ++i) {
    // Line from the exit of corner i to the entry of corner i + 1, then that corner's arc.
    const size_t j = (i + 1) % n;
    const Eigen::Vector2d d = entry[j] - exit[i];
    const Eigen::Vector2d edge = w[j] - w[i];
    if (d.dot(edge) < -1e-9) {
      throw Error("RoundedPath: corner radius " + std::to_string(radius_m) + " m does not fit edge " + std::to_string(i) +
                  " (" + std::to_string(edge.norm()) + " m)");
    }
    Segment line;
    line.a = exit[i];
    line.length = d.norm();
    line.direction = line.length > 0 ? Eigen::Vector2d(d / line.length) : Eigen::Vector2d(edge.normalized());
    line.start_s = length_m_;
    length_m_ += line.length;
    segments_.push_back(line);
    Segment arc = arcs[j];
    arc.start_s = length_m_;
    length_m_ += arc.length;
    segments_.push_back(arc);
  }
}

const RoundedPath::Segment& RoundedPath::find(double& s) const {
  s = std::fmod(s, length_m_);
  if (s < 0) s += length_m_;
  auto it = std::upper_bound(segments_.begin(), segments_.end(), s,
                             [](double value, const Segment& seg) { return value < seg.start_s; });
  const Segment& seg = *(it == segments_.begin() ? it : it - 1);
  s -= seg.start_s;
  return seg;
}

Eigen::Vector2d RoundedPath::position(double s_m) const {
  const Segment& seg = find(s_m);
  if (!seg.arc) return seg.a + seg.direction * s_m;
  const double angle = seg.start_angle + (seg.sweep >= 0 ? 1.0 : -1.0) * s_m / seg.radius;
  return seg.center + seg.radius * Eigen::Vector2d(std::cos(angle), std::sin(angle));
}

Eigen::Vector2d RoundedPath::tangent(double s_m) const {
  const Segment& seg = find(s_m);
  if (!seg.arc) return seg.direction;
  const double sign = seg.sweep >= 0 ? 1.0 : -1.0;
  const double angle = seg.start_angle + sign * s_m / seg.radius;
  return sign * Eigen::Vector2d(-std::sin(angle), std::cos(angle));
}

}  // namespace cenote::sim
