// Mass properties of every shape at a uniform density, in closed form.
#include <string>

#include "pba/collide/shape.h"

namespace pba {

namespace {

Mat3 diagonal(double x, double y, double z) {
  Mat3 m(0.0);
  m[0][0] = x, m[1][1] = y, m[2][2] = z;
  return m;
}

}  // namespace

MassProperties mass_properties(const ColliderShape& s, double density, std::string_view where) {
  require_positive(density, field_path(where, "density"));
  s.validate(where);
  MassProperties mp;
  switch (s.type) {
    case ShapeType::Plane:
    case ShapeType::Mesh:
      throw Error(std::string(where) + ": a " + std::string(to_string(s.type)) +
                  " has no volume, so no mass properties (use it as a static shape)");
    case ShapeType::Sphere: {
      // solid ball: I = 2/5 m r^2 about any diameter
      const double r = s.radius;
      mp.volume = 4.0 / 3.0 * kPi * r * r * r;
      mp.mass = density * mp.volume;
      const double i = 0.4 * mp.mass * r * r;
      mp.inertia = diagonal(i, i, i);
      return mp;
    }
    case ShapeType::Box: {
      // solid box of edges 2h: I_xx = m (h_y^2 + h_z^2) / 3
      const Vec3 h = s.half_extents;
      mp.volume = 8 * h.x * h.y * h.z;
      mp.mass = density * mp.volume;
      const Vec3 q = h * h;
      mp.inertia = diagonal(mp.mass * (q.y + q.z) / 3, mp.mass * (q.x + q.z) / 3, mp.mass * (q.x + q.y) / 3);
      return mp;
    }
    case ShapeType::Capsule: {
      // a cylinder of height 2 hh and two hemispheres; a hemisphere about a diameter of its
      // flat face has 2/5 m r^2, its centre of mass is 3r/8 from that face, so by the
      // parallel-axis theorem about the capsule's centre it has
      // m (2/5 r^2 - (3r/8)^2 + (hh + 3r/8)^2) = m (2/5 r^2 + hh^2 + 3/4 r hh)
      const double r = s.radius, hh = s.half_height;
      const double mc = density * kPi * r * r * 2 * hh;
      const double mh = density * 2.0 / 3.0 * kPi * r * r * r;
      mp.volume = kPi * r * r * (2 * hh + 4.0 / 3.0 * r);
      mp.mass = mc + 2 * mh;
      const double axial = 0.5 * mc * r * r + 2 * 0.4 * mh * r * r;
      const double side = mc * (r * r / 4 + hh * hh / 3) + 2 * mh * (0.4 * r * r + hh * hh + 0.75 * r * hh);
      mp.inertia = diagonal(side, axial, side);
      return mp;
    }
    case ShapeType::Hull: return s.hull->mass_properties(density);
    case ShapeType::Compound: {
      // children in the compound frame: masses and centres add, inertias rotate
      // (R I R^T) and shift to the common centre by the parallel-axis theorem
      const auto& ch = s.compound->children;
      std::vector<MassProperties> parts;
      parts.reserve(ch.size());
      Vec3 first(0.0);
      for (std::size_t i = 0; i < ch.size(); ++i) {
        MassProperties c =
            mass_properties(ch[i].shape, density, field_path(where, "children[" + std::to_string(i) + "]"));
        const Mat3 r = glm::mat3_cast(ch[i].pose.rotation);
        c.center = apply(ch[i].pose, c.center);
        c.inertia = r * c.inertia * glm::transpose(r);
        mp.volume += c.volume;
        mp.mass += c.mass;
        first += c.mass * c.center;
        parts.push_back(c);
      }
      mp.center = first / mp.mass;
      for (const MassProperties& c : parts) {
        const Vec3 d = c.center - mp.center;
        mp.inertia += c.inertia + c.mass * (glm::dot(d, d) * Mat3(1.0) - glm::outerProduct(d, d));
      }
      return mp;
    }
  }
  return mp;
}

}  // namespace pba
