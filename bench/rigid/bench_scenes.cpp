// bench_rigid's scene table (see bench_scenes.h): the scenes with the peers' settings.
#include "bench_scenes.h"

#include <algorithm>

#include "pba/rigid_scenes.h"

namespace pba::bench {

namespace {

// below the ground: fell through it
bool below_ground(const Vec3& c) { return c.y < -0.5; }

}  // namespace

std::vector<BenchScene> bench_scenes() {
  std::vector<BenchScene> out;
  // vertical stacks of unit cubes (bullet_rigid_s.cpp, ode_rigid.cpp), sleeping off
  for (const int n : {10, 20, 40})
    out.push_back({.key = "stack" + std::to_string(n), .title = "stack " + std::to_string(n), .steps = 600,
                   .build = [n](RigidBodySystem& s) { return rigid_scenes::vertical_stack(s, n); },
                   .has_top = true, .escaped = below_ground, .unit_mass = true});
  // Jolt's 15-level pyramid of 2 m cubes, falling into place (bullet_rigid_b.cpp: 500 steps)
  out.push_back({.key = "pyramid1240", .title = "Jolt pyramid 15, 1240 boxes", .steps = 500,
                 .build = [](RigidBodySystem& s) { return rigid_scenes::jolt_pyramid(s, 15); },
                 .has_top = true, .top_rest = [] { return rigid_scenes::jolt_pyramid_rest(15); },
                 .escaped = below_ground, .unit_mass = true});
  // the 20-level square pyramid of touching unit cubes (bullet_rigid_p.cpp, mu 0.6: 600 frames,
  // as the Bullet figure was measured; it settles, then rests: the median step is a
  // resting one. ODE takes about 0.7 s a step here: --peer bullet, or --steps 60 for a look)
  out.push_back({.key = "pyramid2870", .title = "square pyramid 20, 2870 boxes", .steps = 600,
                 .build = [](RigidBodySystem& s) { return rigid_scenes::square_pyramid(s, 20); },
                 .has_top = true, .escaped = below_ground, .unit_mass = true});
  // 1000 unit cubes dropped from a 10 x 10 x 10 grid (bullet_rigid_fall.cpp), sleeping off and on
  for (const bool sleep : {false, true})
    out.push_back({.key = sleep ? "fall1000-sleep" : "fall1000", .title = sleep ? "fall 1000, sleep" : "fall 1000",
                   .steps = 600, .sleep = sleep,
                   .build = [](RigidBodySystem& s) { return rigid_scenes::falling_boxes(s, 10); },
                   .escaped = below_ground, .unit_mass = true});
  // the rain of 10,000 boxes and spheres, sleeping on as a game runs it
  out.push_back({.key = "rain10000", .title = "rain 10000 boxes and spheres, sleep", .steps = 600, .sleep = true,
                 .build = [](RigidBodySystem& s) { return rigid_scenes::rain(s, 10000); },
                 .escaped = below_ground});
  // 5000 bodies at 250 m/s in a closed box of 0.2 m walls (the tunnelling soak's scene);
  // Bullet with its continuous collision on, as a user would for such bodies
  const double inner = 10, wall = 0.2;
  out.push_back({.key = "closedbox5000", .title = "closed box, 5000 at 250 m/s, sleep", .steps = 60, .sleep = true,
                 .build = [=](RigidBodySystem& s) { return rigid_scenes::closed_box(s, 5000, 250.0, inner, wall); },
                 .escaped = [=](const Vec3& c) {
                   return std::max(std::abs(c.x), std::max(std::abs(c.y), std::abs(c.z))) >= inner + 0.5 * wall;
                 },
                 .bullet_ccd = true});
  // 1764 mixed convex bodies on the 20,000-triangle sine terrain (bullet_rigid_c.cpp: 500
  // steps, 5 iterations, sleeping on); lost: below the terrain's lowest point or off its edge
  out.push_back({.key = "terrain", .title = "terrain, 1764 on 20000 triangles, sleep", .steps = 500, .sleep = true,
                 .build = [](RigidBodySystem& s) { return rigid_scenes::convex_vs_mesh(s); },
                 .escaped = [](const Vec3& c) { return c.y < -0.5 || std::abs(c.x) > 150 || std::abs(c.z) > 150; },
                 .bullet_iterations = 5, .has_mesh = true});
  return out;
}

}  // namespace pba::bench
