// Helpers shared by the particle samples: world stepping and drawing.
#include "particles_common.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include <imgui.h>

#include "pba/soft.h"

namespace pba::app {

namespace {

Color with_alpha(Color c, float a) { return Color{c.r, c.g, c.b, a}; }
}  // namespace

void TickWorld(World& world, const Settings& settings, double dt) {
  // the integrator follows the Simulation panel; the world keeps its own clock
  if (world.particles().method() != settings.method) world.particles().set_method(settings.method);
  world.tick(world.time(), dt);
}

void DrawParticles(Renderer& r, const ParticleSystem& ps, const DrawFlags& flags, float point_px, double min_radius,
                   std::size_t sphere_limit) {
  if (!flags.particles) return;
  const std::size_t n = ps.size();
  // few particles: lit spheres with shadows
  if (n <= sphere_limit) {
    for (std::size_t i = 0; i < n; ++i) r.sphere(ps.position(i), std::max(ps.radius(i), min_radius), ps.color(i));
    return;
  }
  // many: one screen-space point each, straight from the columns
  const auto xs = ps.xs(), ys = ps.ys(), zs = ps.zs();
  for (std::size_t i = 0; i < n; ++i) r.point(Vec3(xs[i], ys[i], zs[i]), point_px, ps.color(i));
}

void WorldPoints(const World& world, std::vector<Vec3>& out, std::size_t max_points) {
  const ParticleSystem& ps = world.particles();
  const auto* soft = dynamic_cast<const SoftSystem*>(world.find_system(SoftSystem::kName));
  // one stride for all, so the thinning keeps the proportions
  std::size_t total = ps.size();
  if (soft)
    for (std::size_t b = 0; b < soft->size(); ++b) total += soft->at(b).size();
  const std::size_t step = std::max<std::size_t>(1, (total + max_points - 1) / std::max<std::size_t>(max_points, 1));
  for (std::size_t k = 0; k < ps.size(); k += step) out.push_back(ps.position(k));
  if (soft)
    for (std::size_t b = 0; b < soft->size(); ++b)
      for (std::size_t k = 0; k < soft->at(b).size(); k += step) out.push_back(soft->at(b).position(k));
  // the rigid bodies' shapes (their centres; planes are unbounded)
  for (const Collider& c : world.body_colliders())
    if (c.shape.type != ShapeType::Plane) out.push_back(c.end.position);
}

void DrawRigidBodies(Renderer& r, const World& world, const DrawFlags& flags) {
  world.draw_rigid_bodies(r, flags,
                          {.awake = particle_colors::body, .asleep = particle_colors::asleep,
                           .kinematic = particle_colors::moving, .fixed = particle_colors::solid});
}

void DrawColliders(Renderer& r, std::span<const Collider> colliders, std::span<const bool> moving,
                   const DrawFlags& flags) {
  for (std::size_t i = 0; i < colliders.size(); ++i) {
    const Collider& c = colliders[i];
    // moving: as told, else whether the surface moved or moves
    const bool kin = i < moving.size() ? moving[i]
                                       : (glm::length(c.velocity) > 0 || glm::length(c.angular_velocity) > 0 ||
                                          c.begin.position != c.end.position);
    const Color col = kin ? particle_colors::moving : particle_colors::solid;
    // bounds through the library; solids through the library too, except planes: the
    // ground is the app's grid and other planes get a smaller translucent patch
    c.draw(r, col, DrawFlags{.shapes = false, .aabbs = flags.aabbs});
    if (!flags.shapes) continue;
    switch (c.shape.type) {
      case ShapeType::Plane: {
        const Vec3 n = glm::normalize(c.end.rotation * c.shape.normal);
        const double off = c.shape.offset + glm::dot(n, c.end.position);
        // the ground is the app's grid; other planes get a translucent patch
        if (n.y > 0.999 && std::abs(off) < 1e-9) break;
        r.plane(n, off, 4.0, with_alpha(col, 0.45f));
        break;
      }
      default: c.draw(r, col, DrawFlags{.shapes = true, .aabbs = false}); break;
    }
  }
}

Color ForcerColor(ForcerKind kind) {
  switch (kind) {
    case ForcerKind::Fan: return particle_colors::fan;
    case ForcerKind::Vortex: return particle_colors::vortex;
    case ForcerKind::Attractor: return particle_colors::attractor;
  }
  return colors::white;
}

void DrawForcer(Renderer& r, const Forcer& f, double t, const DrawFlags& flags) {
  if (!flags.forcers) return;
  const bool on = f.active(t);
  const Color c = ForcerColor(f.kind);
  const Color edge = with_alpha(c, on ? 0.9f : 0.35f);
  const Quat q = glm::normalize(f.pose.rotation);
  const Vec3 o = f.pose.position;
  // the volume: a faint translucent shell and its outline
  std::vector<Vec3> samples;
  double size = 0;
  switch (f.shape) {
    case ForcerShape::Box: {
      const Vec3 h = f.half_extents;
      r.box(o, h, q, with_alpha(c, on ? 0.10f : 0.05f));
      for (int a = 0; a < 3; ++a)
        for (int s1 = -1; s1 <= 1; s1 += 2)
          for (int s2 = -1; s2 <= 1; s2 += 2) {
            Vec3 p0(0), p1(0);
            const int b = (a + 1) % 3, cc = (a + 2) % 3;
            p0[a] = -h[a], p1[a] = h[a];
            p0[b] = p1[b] = s1 * h[b];
            p0[cc] = p1[cc] = s2 * h[cc];
            r.line(o + q * p0, o + q * p1, edge, 2.0f);
          }
      // arrows on a 3 x 3 x 2 lattice inside
      for (int i = -1; i <= 1; ++i)
        for (int k = -1; k <= 1; k += 2)
          for (int j = -1; j <= 1; j += 2) samples.push_back(Vec3(0.6 * i * h.x, 0.5 * j * h.y, 0.5 * k * h.z));
      size = std::min({h.x, h.y, h.z});
      break;
    }
    case ForcerShape::Cylinder: {
      const int seg = 40;
      for (double y : {-f.half_height, 0.0, f.half_height})
        for (int i = 0; i < seg; ++i) {
          const double a0 = 2 * kPi * i / seg, a1 = 2 * kPi * (i + 1) / seg;
          r.line(o + q * Vec3(f.radius * std::cos(a0), y, f.radius * std::sin(a0)),
                 o + q * Vec3(f.radius * std::cos(a1), y, f.radius * std::sin(a1)), y == 0 ? with_alpha(edge, 0.5f) : edge,
                 2.0f);
        }
      for (int i = 0; i < 8; ++i) {
        const double a = 2 * kPi * i / 8;
        const Vec3 rim(f.radius * std::cos(a), 0, f.radius * std::sin(a));
        r.line(o + q * (rim - Vec3(0, f.half_height, 0)), o + q * (rim + Vec3(0, f.half_height, 0)),
               with_alpha(edge, 0.4f), 1.2f);
      }
      // arrows on two rings at three heights
      for (double y : {-0.6 * f.half_height, 0.0, 0.6 * f.half_height})
        for (int i = 0; i < 6; ++i) {
          const double a = 2 * kPi * (i + 0.5 * (y > 0)) / 6;
          samples.push_back(Vec3(0.7 * f.radius * std::cos(a), y, 0.7 * f.radius * std::sin(a)));
        }
      size = std::min(f.radius, f.half_height);
      break;
    }
    case ForcerShape::Sphere: {
      r.sphere(o, f.radius, with_alpha(c, on ? 0.10f : 0.05f));
      const int seg = 40;
      for (int plane = 0; plane < 3; ++plane)
        for (int i = 0; i < seg; ++i) {
          const double a0 = 2 * kPi * i / seg, a1 = 2 * kPi * (i + 1) / seg;
          Vec3 p0(0), p1(0);
          p0[plane] = f.radius * std::cos(a0), p0[(plane + 1) % 3] = f.radius * std::sin(a0);
          p1[plane] = f.radius * std::cos(a1), p1[(plane + 1) % 3] = f.radius * std::sin(a1);
          r.line(o + q * p0, o + q * p1, with_alpha(edge, 0.6f), 1.5f);
        }
      // arrows on the axes and the diagonals, at 3/4 of the radius
      const double k = 0.75 * f.radius, d = k / std::sqrt(3.0);
      for (int a = 0; a < 3; ++a)
        for (int s = -1; s <= 1; s += 2) {
          Vec3 p(0);
          p[a] = s * k;
          samples.push_back(p);
        }
      for (int i = 0; i < 8; ++i) samples.push_back(Vec3((i & 1) ? d : -d, (i & 2) ? d : -d, (i & 4) ? d : -d));
      size = f.radius;
      break;
    }
  }
  // arrows along the force at the sample points, scaled to the volume
  const double len = 0.45 * size;
  const double s = std::max(std::abs(f.strength), 1e-12);
  for (const Vec3& local : samples) {
    const Vec3 p = o + q * local;
    Forcer always = f;
    always.pulse_period = 0;  // direction even while a cannon is off
    const Vec3 force = always.force_at(p, t);
    const double m = glm::length(force);
    if (m <= 1e-12 * s) continue;
    const Vec3 d = force / m;
    const double l = len * std::clamp(m / s, 0.35, 1.0);
    r.arrow(p - 0.5 * l * d, p + 0.5 * l * d, 0.3 * l, edge);
  }
}

void DrawWindField(Renderer& r, const Vec3& wind, const Vec3& lo, const Vec3& hi, int n, int m) {
  const double speed = glm::length(wind);
  if (speed < 1e-6) return;
  // arrows 0.12 s of travel long: their length is the wind speed
  const Vec3 d = wind * 0.12;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const double fx = n == 1 ? 0.5 : static_cast<double>(i) / (n - 1);
      const double fy = m == 1 ? 0.5 : static_cast<double>(j) / (m - 1);
      const Vec3 p(lo.x + fx * (hi.x - lo.x), lo.y + fy * (hi.y - lo.y), lo.z + 0.5 * (hi.z - lo.z));
      r.arrow(p - 0.5 * d, p + 0.5 * d, std::min(0.18, 0.4 * glm::length(d)), with_alpha(particle_colors::wind, 0.85f));
    }
}

double OptionNumber(const SampleContext& ctx, const std::string& key, double fallback, double lo, double hi) {
  // (a key given with no value, "spin=", is refused: it ran the default)
  const std::string v = ctx.option(key, "");
  if (v.empty() && !ctx.options.count(key)) return fallback;
  char* end = nullptr;
  const double x = std::strtod(v.c_str(), &end);
  if (v.empty() || end != v.c_str() + v.size() || !std::isfinite(x) || x < lo || x > hi) {
    char buf[160];
    std::snprintf(buf, sizeof buf, ": expected a number in [%g, %g]", lo, hi);
    throw Error("--option " + key + "=" + v + buf);
  }
  return x;
}

int OptionInteger(const SampleContext& ctx, const std::string& key, int fallback, int lo, int hi) {
  const std::string v = ctx.option(key, "");
  if (v.empty() && !ctx.options.count(key)) return fallback;
  char* end = nullptr;
  const double x = std::strtod(v.c_str(), &end);
  // a count or a size given with a fraction is a mistake, not a number to round; out of its
  // range or no number at all, it is refused as the integer it must be too (it was "expected a
  // number in" the range, which a fraction within it also is)
  if (v.empty() || end != v.c_str() + v.size() || !std::isfinite(x) || x < lo || x > hi || x != std::floor(x)) {
    char buf[160];
    std::snprintf(buf, sizeof buf, ": expected an integer in [%d, %d]", lo, hi);
    throw Error("--option " + key + "=" + v + buf);
  }
  return static_cast<int>(x);
}

bool OptionFlag(const SampleContext& ctx, const std::string& key, bool fallback) {
  const std::string v = ctx.option(key, "");
  if (v.empty() && !ctx.options.count(key)) return fallback;
  if (v != "0" && v != "1") throw Error("--option " + key + "=" + v + ": expected 0 (off) or 1 (on)");
  return v == "1";
}

PlotSeries Series(const float* x, const float* y, int count, Color color, float width) {
  PlotSeries s;
  s.x = x, s.y = y, s.count = count, s.color = color, s.width = width;
  return s;
}

std::string Thousands(long long n) {
  // the result built front to back in one string: the sign, then the digits with a space
  // before each group of three from the right. (Prepending the sign with "-" + s, which
  // inserts into s at its front, drew GCC's -Wrestrict in the release build; and -n
  // overflowed at the smallest long long, so the magnitude is taken unsigned.)
  const unsigned long long magnitude = n < 0 ? 0ull - static_cast<unsigned long long>(n) : static_cast<unsigned long long>(n);
  const std::string digits = std::to_string(magnitude);
  std::string s;
  s.reserve(digits.size() + digits.size() / 3 + 1);
  if (n < 0) s.push_back('-');
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) s.push_back(' ');
    s.push_back(digits[i]);
  }
  return s;
}

void ProfileReadout(const World& world) {
  const WorldProfile& p = world.profile();
  const ParticleSystem& ps = world.particles();
  ImGui::Text("step %.2f ms: emit %.2f, recycle %.2f", 1e3 * p.total, 1e3 * p.emit, 1e3 * p.recycle);
  // semi-implicit Euler runs the fused kernel, whose collisions are timed with the
  // integration (ParticleProfile::integrate); the other integrators time them apart
  if (ps.method() == Method::SemiImplicitEuler)
    ImGui::Text("particles: integrate + collide %.2f ms (fused), %zu contacts", 1e3 * (p.integrate + p.collide),
                ps.contacts());
  else
    ImGui::Text("particles: integrate %.2f, collide %.2f ms, %zu contacts", 1e3 * p.integrate, 1e3 * p.collide,
                ps.contacts());
  // the rigid stage, when entities have bodies (the colliders' stand-ins do not count)
  bool bodies = false;
  for (std::size_t i = 0; i < world.rigid().size() && !bodies; ++i) bodies = world.valid(world.rigid().id_at(i));
  if (bodies)
    ImGui::Text("rigid bodies %.2f ms, %zu manifolds", 1e3 * p.stages[static_cast<int>(WorldStage::Rigid)],
                world.rigid().manifold_count());
  // the other stages, when the world has them (a constraint pass costs microseconds)
  if (p.constraints > 1e-5 || world.find_system(SoftSystem::kName))
    ImGui::Text("constraints %.2f, soft bodies %.2f ms", 1e3 * p.constraints, 1e3 * p.systems);
}

}  // namespace pba::app
