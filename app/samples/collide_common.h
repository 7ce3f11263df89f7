// Shared pieces of the collide samples: the shape menu, a fixed demo hull, and drawing of
// any convex shape at a pose through the renderer.
#pragma once

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "pba/collide/narrow_phase.h"
#include "renderer.h"

namespace pba::app {

/// The shapes the collide samples offer.
inline constexpr std::array<const char*, 4> kShapeNames = {"sphere", "capsule", "box", "hull"};

/// The demo hull: a squashed, cut icosahedron-like cloud (the same every run).
inline std::shared_ptr<const ConvexHull> demo_hull() {
  std::vector<Vec3> pts;
  const double t = (1 + std::sqrt(5.0)) / 2;
  const Vec3 ico[12] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                        {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (const Vec3& v : ico) pts.push_back(glm::normalize(v) * Vec3(0.55, 0.4, 0.45));
  pts.push_back({0.2, 0.55, 0.1});
  return ConvexHull::build(pts, "demo hull");
}

/// Shape number `k` of kShapeNames (hull: `hull`).
inline ColliderShape demo_shape(int k, const std::shared_ptr<const ConvexHull>& hull) {
  switch (k) {
    case 0: return ColliderShape::sphere(0.45);
    case 1: return ColliderShape::capsule(0.4, 0.3);
    case 2: return ColliderShape::box(Vec3(0.5, 0.35, 0.4));
    default: return ColliderShape::convex(hull);
  }
}

/// Index of `name` in kShapeNames; throws Error naming the option otherwise.
inline int shape_index(const std::string& name, const char* option) {
  for (int k = 0; k < int(kShapeNames.size()); ++k)
    if (name == kShapeNames[std::size_t(k)]) return k;
  throw Error(std::string("--option ") + option + "=" + name + ": expected sphere, capsule, box or hull");
}

/// Draws a convex shape at a pose (hull faces as triangle fans with their edges on top).
inline void draw_shape(Renderer& r, const ColliderShape& s, const Pose& p, Color c) {
  switch (s.type) {
    case ShapeType::Sphere: r.sphere(p.position, s.radius, c); break;
    case ShapeType::Capsule: {
      const Vec3 u = p.rotation * Vec3(0, s.half_height, 0);
      r.capsule(p.position - u, p.position + u, s.radius, c);
      break;
    }
    case ShapeType::Box: r.box(p.position, s.half_extents, p.rotation, c); break;
    case ShapeType::Hull: {
      const ConvexHull& h = *s.hull;
      const auto v = h.vertices();
      const auto e = h.edges();
      for (const auto& f : h.faces()) {
        const Vec3 a = apply(p, v[e[f.edge].origin]);
        std::uint32_t k = e[f.edge].next;
        while (e[k].next != f.edge) {
          r.triangle(a, apply(p, v[e[k].origin]), apply(p, v[e[e[k].next].origin]), c);
          k = e[k].next;
        }
      }
      const Color edge = Color::rgb(c.r * 0.5f, c.g * 0.5f, c.b * 0.5f);
      for (std::size_t i = 0; i < e.size(); i += 2) r.line(apply(p, v[e[i].origin]), apply(p, v[e[i + 1].origin]), edge);
      break;
    }
    default: break;
  }
}

}  // namespace pba::app
