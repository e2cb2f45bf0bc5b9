#include "mmlio/sim/scenarios.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "mmlio/core/error.hpp"

namespace mmlio::sim {

namespace {

using V3 = Eigen::Vector3d;

struct Builder {
  std::vector<Box> boxes;
  double lift_m = 0.0;  // added to every z: the storey being built
  void add(double x0, double y0, double z0, double x1, double y1, double z1, float reflectivity) {
    z0 += lift_m;
    z1 += lift_m;
    boxes.push_back({V3(std::min(x0, x1), std::min(y0, y1), std::min(z0, z1)),
                     V3(std::max(x0, x1), std::max(y0, y1), std::max(z0, z1)), reflectivity});
  }
  /// A wall along x on the line y = y_face, solid away from the room (side = +1: y > y_face),
  /// from x0 to x1, with door recesses (width, depth) starting at each of door_x.
  void wallAlongX(double x0, double x1, double y_face, int side, double h, const std::vector<double>& door_x,
                  double door_w, double depth, float refl, float door_refl) {
    const double thick = depth + 0.2;
    double x = x0;
    for (double d : door_x) {
      if (d > x) add(x, y_face, 0, d, y_face + side * thick, h, refl);
      add(d, y_face + side * depth, 0, d + door_w, y_face + side * thick, 2.1, door_refl);  // the door
      add(d, y_face + side * 0.0, 2.1, d + door_w, y_face + side * thick, h, refl);         // lintel
      x = d + door_w;
    }
    if (x1 > x) add(x, y_face, 0, x1, y_face + side * thick, h, refl);
  }
};

// Small deterministic generator for clutter placement (independent of the user's seed: the
// scene of a scenario is fixed).
struct Lcg {
  std::uint64_t s;
  double uniform(double lo, double hi) {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    return lo + (hi - lo) * static_cast<double>(s >> 11) * (1.0 / 9007199254740992.0);
  }
};

double distanceToRoute(double x, double y, const std::vector<Waypoint>& route) {
  double best = 1e9;
  for (size_t i = 1; i < route.size(); ++i) {
    const Eigen::Vector2d a(route[i - 1].x_m, route[i - 1].y_m), b(route[i].x_m, route[i].y_m), p(x, y);
    const Eigen::Vector2d ab = b - a;
    const double u = ab.squaredNorm() > 0 ? std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
    best = std::min(best, (a + u * ab - p).norm());
  }
  return best;
}

// Waypoints through positions, heading along the path (mean of incoming and outgoing legs),
// with yaw unwrapped from yaw0.
std::vector<Waypoint> route(const std::vector<Eigen::Vector2d>& points, double yaw0) {
  std::vector<Waypoint> out;
  double prev = yaw0;
  auto unwrapNear = [](double a, double ref) { return a + 2 * M_PI * std::round((ref - a) / (2 * M_PI)); };
  for (size_t i = 0; i < points.size(); ++i) {
    double yaw;
    if (i == 0) {
      yaw = yaw0;
    } else {
      const Eigen::Vector2d in = points[i] - points[i - 1];
      const double h_in = unwrapNear(std::atan2(in.y(), in.x()), prev);
      double h_out = h_in;
      if (i + 1 < points.size()) {
        const Eigen::Vector2d o = points[i + 1] - points[i];
        h_out = unwrapNear(std::atan2(o.y(), o.x()), h_in);
      }
      yaw = 0.5 * (h_in + h_out);
    }
    out.push_back({points[i].x(), points[i].y(), yaw});
    prev = yaw;
  }
  return out;
}

void addClutter(Builder& b, Lcg& rng, int count, double x0, double x1, double y0, double y1,
                const std::vector<Waypoint>& path, double clearance_m, double max_size_m, double max_h_m) {
  for (int n = 0, tries = 0; n < count && tries < 20 * count; ++tries) {
    const double sx = rng.uniform(0.3, max_size_m), sy = rng.uniform(0.3, max_size_m);
    const double h = rng.uniform(0.3, max_h_m);
    const double x = rng.uniform(x0, x1 - sx), y = rng.uniform(y0, y1 - sy);
    const float refl = static_cast<float>(rng.uniform(20, 230));
    bool clear = true;
    for (double u : {0.0, 0.5, 1.0})
      for (double v : {0.0, 0.5, 1.0})
        if (distanceToRoute(x + u * sx, y + v * sy, path) < clearance_m) clear = false;
    if (!clear) continue;
    b.add(x, y, 0, x + sx, y + sy, h, refl);
    ++n;
  }
}

}  // namespace

WalkConfig handheldWalk() {
  WalkConfig w;
  w.bob_amplitude_m = 0.03;    // a walker's head and hands rise and fall ~3 cm per step
  w.bob_period_s = 1.0 / 1.9;  // at ~1.9 steps per second
  w.sway_rad = 3.0 * M_PI / 180;
  w.nod_rad = 3.0 * M_PI / 180;
  w.yaw_wobble_rad = 2.0 * M_PI / 180;
  w.knot_interval_s = 0.04;
  w.yaw_rate_rad_s = 150.0 * M_PI / 180;
  return w;
}

namespace {

Scenario office() {
  Scenario s;
  s.name = "office";
  const double L = 12.0, W = 3.7, H = 2.8;
  Builder b;
  b.add(-0.3, -0.3, -0.2, L + 0.5, W + 0.5, 0, 60);      // floor
  b.add(-0.3, -0.3, H, L + 0.5, W + 0.5, H + 0.2, 200);  // ceiling
  b.add(-0.3, -0.3, 0, 0, W + 0.5, H, 150);              // west wall
  b.add(L, -0.3, 0, L + 0.3, W + 0.5, H, 150);           // east wall
  b.wallAlongX(0, L, 0.0, -1, H, {}, 0, 0, 140, 0);
  b.wallAlongX(0, L, W, +1, H, {5.0}, 0.9, 0.25, 140, 90);  // north wall with the door recess
  // Desks (top + two side panels) along the south wall and one on the north side.
  for (double x : {0.9, 3.3, 7.4}) {
    b.add(x, 0, 0.72, x + 1.4, 0.75, 0.76, 110);
    b.add(x, 0, 0, x + 0.04, 0.75, 0.72, 80);
    b.add(x + 1.36, 0, 0, x + 1.4, 0.75, 0.72, 80);
    b.add(x + 0.5, 0.1, 0.76, x + 0.55, 0.6, 1.15, 30);  // a monitor
  }
  b.add(8.4, W - 0.75, 0.72, 9.8, W, 0.76, 110);
  b.add(8.4, W - 0.75, 0, 8.44, W, 0.72, 80);
  b.add(9.76, W - 0.75, 0, 9.8, W, 0.72, 80);
  // Chairs, cabinets, a shelf, a thin TV on the north wall, ceiling lamps.
  b.add(1.4, 0.85, 0, 1.85, 1.25, 0.48, 50);
  b.add(7.9, 0.8, 0, 8.35, 1.2, 0.48, 50);
  b.add(10.7, 0, 0, 11.9, 0.5, 1.9, 170);
  b.add(0.05, 2.4, 0, 0.55, 3.6, 1.2, 180);
  b.add(6.1, W - 0.35, 0, 7.3, W, 2.0, 120);
  b.add(2.0, W - 0.05, 1.2, 3.3, W, 1.9, 15);   // TV: 5 cm thick
  b.add(L - 0.03, 1.2, 0.9, L, 2.6, 2.0, 240);  // whiteboard on the east wall
  for (double x : {1.8, 5.1, 8.7}) b.add(x, 1.5, H - 0.06, x + 1.2, 1.8, H, 250);
  b.add(4.2, 0, H - 0.35, 4.5, W, H, 150);  // a ceiling beam
  s.boxes = b.boxes;

  s.walk.speed_m_s = 0.8;
  s.walk.yaw_rate_rad_s = M_PI / 2;  // U-turns at 90 deg/s
  s.waypoints = {{1.5, 1.85, 0},           {6.0, 1.6, 0.05},     {10.2, 1.75, 0},      {10.4, 1.95, M_PI},
                 {6.0, 2.15, M_PI - 0.05}, {1.7, 2.0, M_PI},     {1.5, 1.8, 2 * M_PI}, {5.5, 1.9, 2 * M_PI},
                 {5.7, 2.0, 3 * M_PI},     {1.5, 1.85, 4 * M_PI}};
  return s;
}

Scenario corridor() {
  Scenario s;
  s.name = "corridor";
  const double L = 60.0, half = 1.2, H = 2.8, end_half = 3.0, end_x = 66.0;
  Builder b;
  b.add(-0.5, -end_half - 0.5, -0.2, end_x + 0.5, end_half + 0.5, 0, 60);
  b.add(-0.5, -end_half - 0.5, H, end_x + 0.5, end_half + 0.5, H + 0.2, 200);
  b.add(-0.3, -half - 0.5, 0, 0, half + 0.5, H, 150);  // start wall
  b.add(end_x, -end_half - 0.3, 0, end_x + 0.3, end_half + 0.3, H, 150);
  b.add(L, end_half, 0, end_x, end_half + 0.3, H, 150);  // end area side walls
  b.add(L, -end_half - 0.3, 0, end_x, -end_half, H, 150);
  b.add(L - 0.45, half, 0, L, end_half, H, 150);  // shoulders
  b.add(L - 0.45, -end_half, 0, L, -half, H, 150);
  b.wallAlongX(0, L - 0.45, -half, -1, H, {4.3, 9.1, 16.4, 21.0, 27.8, 35.5, 39.2, 46.9, 53.3}, 1.0, 0.25, 140, 70);
  b.wallAlongX(0, L - 0.45, half, +1, H, {6.8, 12.9, 19.2, 25.1, 31.4, 37.0, 43.6, 50.2, 56.1}, 1.0, 0.25, 140, 90);
  // Lamps at irregular spacing, notice boards, extinguishers, a bench, radiators.
  for (double x :
       {2.0, 5.1, 8.6, 11.8, 15.4, 18.7, 22.3, 25.2, 28.9, 32.1, 35.8, 38.7, 42.4, 45.3, 49.0, 52.2, 55.9, 59.1})
    b.add(x, -0.2, H - 0.05, x + 1.2, 0.2, H, 250);
  for (double x : {3.0, 14.2, 29.5, 41.0, 48.7}) b.add(x, -half, 1.0, x + 0.9, -half + 0.03, 1.7, 220);
  for (double x : {10.5, 23.4, 33.3, 44.9, 57.5}) b.add(x, half - 0.15, 0.3, x + 0.2, half, 0.9, 200);
  b.add(17.5, -half, 0, 19.0, -half + 0.4, 0.45, 100);
  for (double x : {7.5, 26.2, 38.1, 51.0}) b.add(x, half - 0.1, 0.15, x + 1.0, half, 0.75, 130);
  // End area: a pillar and boxes, off the turn.
  b.add(64.8, 2.0, 0, 65.4, 2.6, H, 160);
  b.add(61.0, -2.9, 0, 62.2, -2.3, 1.1, 90);
  b.add(64.5, -2.8, 0, 65.9, -1.8, 0.8, 120);
  s.boxes = b.boxes;

  s.walk.speed_m_s = 1.1;
  s.walk.yaw_rate_rad_s = 1.2;
  s.waypoints = {
      {6.0, 0.0, 0},           {40.0, -0.15, 0},  {60.5, 0.0, 0},    {62.5, -0.7, 0.6}, {63.6, 0.2, M_PI / 2 + 0.2},
      {62.3, 0.9, M_PI - 0.3}, {60.5, 0.3, M_PI}, {30.0, 0.2, M_PI}, {6.2, 0.1, M_PI},  {6.0, 0.0, 2 * M_PI}};
  return s;
}

// The corridor walked from a blind start: the rig stands 0.65 m in front of the start wall (the
// solid-state LiDAR 0.6 m from it, seeing nothing else), sways +-15 deg for about 4 s, turns
// round, walks the corridor and its U-turn, and comes back into the same dead end.
Scenario corridorBlind() {
  Scenario s = corridor();
  s.name = "corridor_blind";
  const double x0 = 0.65, sway = 15.0 * M_PI / 180.0;
  std::vector<Waypoint> w = {{x0, 0.0, M_PI}};
  for (int i = 0; i < 8; ++i) w.push_back({x0, 0.0, M_PI + (i % 2 == 0 ? sway : -sway)});
  w.push_back({x0, 0.0, M_PI});
  w.push_back({x0, 0.0, 2 * M_PI});
  for (std::size_t i = 0; i + 1 < s.waypoints.size(); ++i) {
    Waypoint p = s.waypoints[i];
    p.yaw_rad += 2 * M_PI;
    w.push_back(p);
  }
  w.push_back({x0, 0.0, 3 * M_PI});
  s.waypoints = w;
  return s;
}

Scenario hall() {
  Scenario s;
  s.name = "hall";
  const double L = 127.0, W = 35.0, H = 8.0;
  const double px0 = -12.0, py0 = 15.0, py1 = 18.0, pH = 3.0;  // passage
  Builder b;
  b.add(px0 - 0.5, -0.5, -0.2, L + 0.5, W + 0.5, 0, 60);
  b.add(-0.3, -0.5, H, L + 0.5, W + 0.5, H + 0.3, 190);
  b.add(px0 - 0.5, py0 - 0.5, pH, 0, py1 + 0.5, pH + 0.3, 190);  // passage ceiling
  b.add(L, -0.5, 0, L + 0.5, W + 0.5, H, 150);                   // east wall
  b.add(-0.5, -0.5, 0, L, 0, H, 140);                            // south wall
  b.add(-0.5, W, 0, L, W + 0.5, H, 140);                         // north wall
  b.add(-0.5, 0, 0, 0, py0, H, 150);                             // west wall around the opening
  b.add(-0.5, py1, 0, 0, W, H, 150);
  b.add(-0.5, py0, pH, 0, py1, H, 150);
  b.add(px0 - 0.3, py0 - 0.3, 0, px0, py1 + 0.3, pH, 120);  // passage end wall
  b.wallAlongX(px0, -0.5, py0, -1, pH, {-5.5}, 1.0, 0.25, 130, 80);
  b.wallAlongX(px0, -0.5, py1, +1, pH, {-3.2}, 1.0, 0.25, 130, 90);
  b.add(-8.0, py1 - 0.35, 0, -7.2, py1, 1.0, 210);  // passage clutter, behind the start
  b.add(-2.5, py0, 1.4, -1.6, py0 + 0.05, 2.0, 230);
  // Pillars, ceiling trusses, a balcony, shelves along the walls.
  for (double y : {6.0, 12.0, 23.0, 29.0})
    for (int i = 0; i <= 12; ++i) {
      const double x = 5.0 + 10.0 * i;
      b.add(x - 0.3, y - 0.3, 0, x + 0.3, y + 0.3, H, 170);
    }
  for (int i = 0; i <= 12; ++i) b.add(10.0 * i + 1.0, 0, H - 0.8, 10.0 * i + 1.3, W, H, 180);
  b.add(20.0, W - 2.0, 4.0, 100.0, W, 4.3, 100);
  for (double x : {3.0, 33.0, 71.0, 104.0}) b.add(x, 0, 0, x + 6.0, 0.8, 2.4, 110);
  for (double x : {14.0, 52.0, 88.0}) b.add(x, W - 0.8, 0, x + 8.0, W, 2.4, 110);

  const std::vector<Eigen::Vector2d> loop = {{-10.3, 16.5}, {-2.0, 16.5}, {10.0, 16.5}, {40.0, 9.0},  {48.0, 17.0},
                                             {40.0, 26.0},  {10.0, 24.0}, {3.0, 17.0},  {-2.0, 16.6}, {-10.3, 16.5}};
  s.waypoints.push_back({-10.5, 16.5, M_PI});  // facing the passage end wall, 1.5 m away
  for (const Waypoint& w : route(loop, 0.0)) s.waypoints.push_back(w);
  // The loop turns left by a half turn in total: the walk ends facing the end wall again.
  s.waypoints.back().yaw_rad = M_PI;
  s.waypoints.push_back({-10.5, 16.5, M_PI});
  Lcg rng{12345};
  addClutter(b, rng, 70, 1.0, L - 1.0, 1.0, W - 1.0, s.waypoints, 2.0, 3.0, 2.5);
  s.boxes = b.boxes;
  s.walk.speed_m_s = 1.0;
  s.walk.yaw_rate_rad_s = 1.2;
  return s;
}

// Two storeys 3 m apart with the same plan (a corridor along the south wall, a room off it through
// an open doorway) joined by a switch-back staircase at the west end: two flights of nine 0.167 m
// risers and 0.28 m treads with a landing between them. The slab between the storeys hides each
// floor from the other. Carried by hand: up, into the upper room, along the upper corridor, back
// down and home.
Scenario stairs() {
  Scenario s;
  s.name = "stairs";
  const double storey = 3.0, slab = 0.25, ceiling = storey - slab, L = 20.0, cw = 2.4;
  const double x_top = -0.5, tread = 0.28, rise = 1.5 / 9, x_landing = x_top - 8 * tread, x_west = -4.0;
  Builder b;
  b.add(x_west - 0.3, -0.3, -0.2, L + 0.3, 6.7, 0, 60);                         // ground floor
  b.add(x_top, -0.3, storey - slab, L + 0.3, 6.7, storey, 70);                  // slab between the storeys
  b.add(x_west - 0.3, -0.3, 2 * storey - slab, L + 0.3, 6.7, 2 * storey, 200);  // roof
  b.add(x_west - 0.3, -0.3, 0, L + 0.3, 0, 2 * storey, 150);                    // south wall, both storeys
  b.add(x_west - 0.3, 0, 0, x_west, cw + 0.2, 2 * storey, 150);                 // stairwell west wall
  b.add(x_west, cw, 0, x_top, cw + 0.2, 2 * storey, 140);                       // stairwell north wall
  b.add(L, 0, 0, L + 0.3, 6.7, 2 * storey, 150);                                // east wall
  // The staircase: solid flights, the landing, a divider wall between the flights.
  for (int k = 0; k < 8; ++k) {
    b.add(x_top - (k + 1) * tread, 0, 0, x_top - k * tread, 1.15, (k + 1) * rise, 100);                 // up west
    b.add(x_landing + k * tread, 1.25, 0, x_landing + (k + 1) * tread, cw, 1.5 + (k + 1) * rise, 100);  // up east
  }
  b.add(x_west, 0, 0, x_landing, cw, 1.5, 90);
  b.add(x_landing, 1.15, 0, x_top, 1.25, 4.0, 160);
  // Each storey: the corridor's north wall with a doorway at x 9-10 into a room (x 6-14), a north
  // wall; furniture that differs between the storeys, so the floors look alike but not the same.
  for (int floor = 0; floor < 2; ++floor) {
    b.lift_m = floor * storey;
    b.add(x_top - 0.2, cw, 0, 9.0, cw + 0.2, ceiling, 140);
    b.add(10.0, cw, 0, L, cw + 0.2, ceiling, 140);
    b.add(9.0, cw, 2.1, 10.0, cw + 0.2, ceiling, 140);        // lintel
    b.add(5.8, cw + 0.2, 0, 6.0, 6.4, ceiling, 150);          // room west wall
    b.add(14.0, cw + 0.2, 0, 14.2, 6.4, ceiling, 150);        // room east wall
    b.add(x_top - 0.2, 6.4, 0, L, 6.7, ceiling, 150);         // north wall
    b.add(x_top - 0.2, cw + 0.2, 0, 5.8, 6.4, ceiling, 120);  // solid beside the room
    b.add(14.2, cw + 0.2, 0, L, 6.4, ceiling, 120);
    for (double x : {2.0, 6.5, 11.0, 15.5}) b.add(x, 0.9, ceiling - 0.05, x + 1.2, 1.3, ceiling, 250);  // lamps
    if (floor == 0) {
      b.add(6.2, 5.6, 0, 8.0, 6.4, 0.75, 110);         // desk
      b.add(12.2, 2.6, 0, 13.9, 3.2, 1.9, 170);        // cabinet
      b.add(3.0, 0, 0, 4.2, 0.4, 1.1, 130);            // bench in the corridor
      b.add(16.0, cw - 0.1, 1.0, 17.0, cw, 1.7, 220);  // notice board
    } else {
      b.add(10.5, 5.5, 0, 13.5, 6.4, 0.75, 110);  // a long desk
      b.add(6.1, 2.6, 0, 6.6, 4.0, 1.9, 180);     // shelf
      b.add(7.5, 0, 0, 8.3, 0.3, 0.9, 200);       // radiator
      b.add(12.5, cw - 0.1, 0.2, 13.5, cw, 0.8, 130);
    }
  }
  b.lift_m = 0.0;
  s.boxes = b.boxes;

  const double up = -0.12, down = 0.3;  // looking up the flight / down at the steps, rad
  const double z1 = 1.5, z2 = storey;
  s.waypoints = {{12.0, 1.2, M_PI},
                 {0.4, 0.6, M_PI},
                 {x_top + 0.1, 0.6, M_PI, 0, up},
                 {x_landing - 0.05, 0.6, M_PI, z1, up},
                 {-3.4, 0.7, M_PI, z1},
                 {-3.5, 1.2, M_PI / 2, z1},
                 {-3.4, 1.8, 0, z1},
                 {x_landing + 0.05, 1.8, 0, z1, up},
                 {x_top - 0.1, 1.8, 0, z2, up},
                 {8.5, 1.5, 0, z2},
                 {9.5, 1.7, M_PI / 2, z2},
                 {9.5, 4.6, M_PI / 2, z2},
                 {9.5, 4.7, 3 * M_PI / 2, z2},
                 {9.5, 1.6, 3 * M_PI / 2, z2},
                 {10.5, 1.2, 2 * M_PI, z2},
                 {17.5, 1.2, 2 * M_PI, z2},
                 {18.0, 1.3, 3 * M_PI, z2},
                 {x_top + 0.3, 1.8, 3 * M_PI, z2},
                 {x_top - 0.1, 1.8, 3 * M_PI, z2, down},
                 {x_landing + 0.05, 1.8, 3 * M_PI, z1, down},
                 {-3.4, 1.8, 3 * M_PI, z1},
                 {-3.5, 1.2, 3.5 * M_PI, z1},
                 {-3.4, 0.6, 4 * M_PI, z1},
                 {x_landing - 0.05, 0.6, 4 * M_PI, z1, down},
                 {x_top + 0.1, 0.6, 4 * M_PI, 0, down},
                 {1.0, 0.7, 4 * M_PI},
                 {11.5, 1.2, 4 * M_PI},
                 {12.0, 1.2, 5 * M_PI}};
  s.walk = handheldWalk();
  s.walk.speed_m_s = 0.9;
  s.walk.yaw_rate_rad_s = 1.5;
  return s;
}

// A hall with a ramp (1:12, 4.8 deg) up to a platform 1 m high, driven like a robot: up the
// ramp, round on the platform, down and home. The rig pitches with the slope. The ramp is built
// of 2 cm steps (boxes are axis-aligned), below the LiDARs' range noise.
Scenario ramp() {
  Scenario s;
  s.name = "ramp";
  const double L = 30.0, W = 8.0, H = 4.5, rise = 1.0, x0 = 8.0, run = 12.0, y0 = 1.8, y1 = 4.2;
  Builder b;
  b.add(-0.3, -0.3, -0.2, L + 0.3, W + 0.3, 0, 60);
  b.add(-0.3, -0.3, H, L + 0.3, W + 0.3, H + 0.2, 200);
  b.add(-0.3, -0.3, 0, 0, W + 0.3, H, 150);
  b.add(L, -0.3, 0, L + 0.3, W + 0.3, H, 150);
  b.add(0, -0.3, 0, L, 0, H, 140);
  b.add(0, W, 0, L, W + 0.3, H, 140);
  const int steps = 50;
  for (int k = 0; k < steps; ++k)
    b.add(x0 + run * k / steps, y0, 0, x0 + run * (k + 1) / steps, y1, rise * (k + 1) / steps, 100);
  b.add(x0 + run, 0.8, 0, 28.5, 6.0, rise, 110);                                      // the platform
  b.add(x0 + run, 5.9, rise, 28.5, 6.0, rise + 1.0, 220);                             // its railing (a plate)
  for (double x : {4.0, 14.0, 24.0}) b.add(x - 0.25, 6.8, 0, x + 0.25, 7.3, H, 170);  // pillars
  b.add(2.0, 6.5, 0, 5.0, 7.6, 1.8, 120);                                             // shelves
  b.add(10.0, 0.2, 0, 13.0, 0.8, 1.2, 130);
  b.add(22.0, 1.0, rise, 23.2, 1.8, rise + 0.9, 90);  // crates on the platform
  b.add(26.0, 4.4, rise, 27.0, 5.4, rise + 1.5, 160);
  for (double x : {3.0, 9.0, 15.0, 21.0, 27.0}) b.add(x, 3.8, H - 0.05, x + 1.2, 4.2, H, 250);  // lamps
  s.boxes = b.boxes;
  const double slope = std::atan2(rise, run), yc = 0.5 * (y0 + y1);
  s.waypoints = {{3.0, yc, 0},
                 {x0 - 0.6, yc, 0},
                 {x0 + 0.4, yc, 0, rise * 0.4 / run, -slope},
                 {x0 + run - 0.4, yc, 0, rise * (run - 0.4) / run, -slope},
                 {x0 + run + 0.6, yc, 0, rise},
                 {26.0, yc - 0.3, 0, rise},
                 {26.5, yc + 0.4, M_PI, rise},
                 {x0 + run + 0.6, yc, M_PI, rise},
                 {x0 + run - 0.4, yc, M_PI, rise * (run - 0.4) / run, slope},
                 {x0 + 0.4, yc, M_PI, rise * 0.4 / run, slope},
                 {x0 - 0.6, yc, M_PI},
                 {3.0, yc, M_PI},
                 {3.0, yc, 2 * M_PI}};
  s.walk.speed_m_s = 1.0;
  s.walk.yaw_rate_rad_s = 1.0;
  return s;
}

#include "tiers_indoor08.inc"

// A lab (14.5 x 7.2 x 3 m) driven along a real platform's recorded motion (the TIERS dataset's
// indoor08 ground truth, levelled and smoothed by scripts/level_recorded_motion.py): benches along
// the walls, shelves, two pillars, equipment placed clear of the recorded path.
Scenario lab() {
  Scenario s;
  s.name = "lab";
  const double x0 = -3.0, x1 = 11.5, y0 = -3.0, y1 = 4.2, H = 3.0;
  Builder b;
  b.add(x0 - 0.3, y0 - 0.3, -0.2, x1 + 0.3, y1 + 0.3, 0, 60);
  b.add(x0 - 0.3, y0 - 0.3, H, x1 + 0.3, y1 + 0.3, H + 0.2, 200);
  b.add(x0 - 0.3, y0 - 0.3, 0, x0, y1 + 0.3, H, 150);
  b.add(x1, y0 - 0.3, 0, x1 + 0.3, y1 + 0.3, H, 150);
  b.wallAlongX(x0, x1, y0, -1, H, {1.5}, 1.2, 0.25, 140, 80);
  b.wallAlongX(x0, x1, y1, +1, H, {7.8}, 0.9, 0.25, 140, 90);
  for (double x : {-1.0, 3.5, 8.0}) {  // benches along the south wall, instruments on them
    b.add(x, y0, 0.88, x + 2.4, y0 + 0.8, 0.92, 120);
    b.add(x, y0, 0, x + 0.05, y0 + 0.8, 0.88, 90);
    b.add(x + 2.35, y0, 0, x + 2.4, y0 + 0.8, 0.88, 90);
    b.add(x + 0.6, y0 + 0.1, 0.92, x + 1.1, y0 + 0.5, 1.3, 40);
  }
  b.add(x0, -1.5, 0, x0 + 0.45, 2.5, 2.1, 170);  // shelves on the west wall
  b.add(x1 - 0.6, -2.6, 0, x1, -1.2, 1.8, 110);  // a cabinet and a whiteboard on the east wall
  b.add(x1 - 0.03, 0.2, 0.9, x1, 2.4, 2.0, 240);
  b.add(0.5, y1 - 0.6, 0, 5.5, y1, 1.9, 130);                                    // tall shelves on the north wall
  for (double x : {2.0, 6.5}) b.add(x - 0.25, 2.75, 0, x + 0.25, 3.25, H, 160);  // pillars
  for (double x : {-1.5, 2.5, 6.5, 10.0}) b.add(x, 0.4, H - 0.06, x + 1.2, 0.7, H, 250);
  b.add(4.5, y0, H - 0.4, 4.8, y1, H, 150);  // a beam
  for (const auto& row : kTiersIndoor08) {
    Keyframe k;
    k.t_s = row[0];
    k.p_world = Eigen::Vector3d(row[1], row[2], row[3]);
    k.yaw_rad = row[4];
    k.pitch_rad = row[5];
    k.roll_rad = row[6];
    s.recorded.push_back(k);
  }
  for (std::size_t i = 0; i < s.recorded.size(); i += 5) {
    const Keyframe& k = s.recorded[i];
    s.waypoints.push_back({k.p_world.x(), k.p_world.y(), k.yaw_rad});
  }
  Lcg rng{777};
  addClutter(b, rng, 12, x0 + 0.5, x1 - 0.7, y0 + 0.9, y1 - 0.7, s.waypoints, 0.7, 1.0, 1.4);
  s.boxes = b.boxes;
  s.walk.height_m = 0.7;         // a platform's LiDARs, not a person's
  s.walk.bob_amplitude_m = 0.0;  // the recorded motion carries the platform's own
  s.walk.sway_rad = 0.0;
  s.walk.nod_rad = 0.0;
  return s;
}

}  // namespace

std::vector<std::string> scenarioNames() {
  return {"office", "corridor", "corridor_blind", "hall", "stairs", "ramp", "lab"};
}

Scenario startingAt(Scenario s, int first) {
  if (first == 0) return s;
  if (!s.recorded.empty()) throw Error("scenario '" + s.name + "' follows a recorded motion: it has no other start");
  const int n = static_cast<int>(s.waypoints.size());
  if (first < 0 || first >= n - 1)
    throw Error("scenario '" + s.name + "' has waypoints 0 to " + std::to_string(n - 2) + " to start from, not " +
                std::to_string(first));
  // The last waypoint is the first after whole turns: the part walked again after it keeps them.
  const double turns = s.waypoints.back().yaw_rad - s.waypoints.front().yaw_rad;
  std::vector<Waypoint> route(s.waypoints.begin() + first, s.waypoints.end());
  for (int i = 1; i <= first; ++i) {
    Waypoint w = s.waypoints[static_cast<std::size_t>(i)];
    w.yaw_rad += turns;
    route.push_back(w);
  }
  s.waypoints = std::move(route);
  return s;
}

Scenario carriedByHand(Scenario s) {
  const double speed_m_s = s.walk.speed_m_s;
  s.walk = handheldWalk();
  s.walk.speed_m_s = speed_m_s;
  // Deliberate looks: down at the floor, level, up at the ceiling, level, from waypoint to waypoint.
  const double looks[4] = {0.0, 25.0 * M_PI / 180, 0.0, -20.0 * M_PI / 180};
  for (std::size_t i = 1; i + 1 < s.waypoints.size(); ++i) s.waypoints[i].pitch_rad += looks[i % 4];
  s.name += "+handheld";
  return s;
}

Scenario makeScenario(const std::string& name) {
  if (name == "office") return office();
  if (name == "corridor") return corridor();
  if (name == "corridor_blind") return corridorBlind();
  if (name == "hall") return hall();
  if (name == "stairs") return stairs();
  if (name == "ramp") return ramp();
  if (name == "lab") return lab();
  std::string valid;
  for (const std::string& n : scenarioNames()) valid += (valid.empty() ? "" : ", ") + n;
  throw Error("unknown scenario '" + name + "'; valid scenarios: " + valid);
}

}  // namespace mmlio::sim
