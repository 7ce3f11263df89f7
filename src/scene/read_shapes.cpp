// The scene reader's collider shapes (docs/scene-format.md, "colliders[]"): plane, sphere,
// box and capsule by their parameters, a convex hull by its points, a triangle mesh by its
// vertices and triangles, a compound by its children at local poses. Every error names the
// JSON path of the bad value.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "json_node.h"

namespace pba::scene_detail {

namespace {

// "key[i]: message" or "key: message" from a shape builder called with where = key, to the
// node of that array item (or of the array itself)
[[noreturn]] void fail_at(const Node& array, const std::string& key, const Error& e) {
  const std::string m = e.what();
  if (m.rfind(key + "[", 0) == 0) {
    const std::size_t close = m.find("]", key.size());
    const std::size_t colon = m.find(": ", close);
    if (close != std::string::npos && colon != std::string::npos) {
      const std::string index = m.substr(key.size() + 1, close - key.size() - 1);
      if (!index.empty() && index.find_first_not_of("0123456789") == std::string::npos) {
        const std::size_t i = std::stoul(index);
        if (i < array.size()) array.item(i).fail(m.substr(colon + 2));
      }
    }
  }
  if (m.rfind(key + ": ", 0) == 0) array.fail(m.substr(key.size() + 2));
  array.fail(m);
}

// an array of points [[x, y, z], ...], each finite and within a float's range (the
// particle kernel's contact planes are floats), at least `min` of them
std::vector<Vec3> read_points(const Node& a, std::size_t min, std::size_t max) {
  a.require_array();
  if (a.size() < min) a.fail("needs at least " + std::to_string(min) + " points, got " + std::to_string(a.size()));
  if (a.size() > max) a.fail("at most " + std::to_string(max) + " points, got " + std::to_string(a.size()));
  std::vector<Vec3> p;
  p.reserve(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    p.push_back(a.item(i).vec3());
    require_float(p.back(), a.item(i).where());
  }
  return p;
}

std::shared_ptr<const ConvexHull> read_hull(const Node& n) {
  // the builder's errors (too few, coincident, collinear or coplanar points) by path
  const Node a = n.at("points");
  const std::vector<Vec3> p = read_points(a, 4, std::size_t(1) << 20);
  try {
    return ConvexHull::build(p, "points");
  } catch (const Error& e) {
    fail_at(a, "points", e);
  }
}

std::shared_ptr<const TriangleMesh> read_mesh(const Node& n) {
  // vertices, then triangles of three indices in range, then the builder (degenerate
  // triangles) with its errors by path
  const Node vs = n.at("vertices");
  const std::vector<Vec3> v = read_points(vs, 3, std::size_t(1) << 24);
  const Node ts = n.at("triangles");
  ts.require_array();
  if (ts.size() == 0) ts.fail("a mesh needs at least one triangle, got 0");
  if (ts.size() > (std::size_t(1) << 24)) ts.fail("at most 16777216 triangles, got " + std::to_string(ts.size()));
  std::vector<std::array<std::uint32_t, 3>> t(ts.size());
  for (std::size_t i = 0; i < ts.size(); ++i) {
    const Node tri = ts.item(i);
    if (!tri.raw().is_array() || tri.size() != 3)
      tri.fail("must be an array of 3 vertex indices, got " + Node::type_name(tri.raw()));
    for (std::size_t k = 0; k < 3; ++k)
      t[i][k] = static_cast<std::uint32_t>(tri.item(k).integer(0, static_cast<long long>(v.size()) - 1));
  }
  try {
    return TriangleMesh::build(v, t, "mesh");
  } catch (const Error& e) {
    fail_at(ts, "mesh.triangles", e);
  }
}

}  // namespace

ColliderShape read_shape(const Node& n, bool child, int depth) {
  // the type; a compound's children are solids (no planes, no meshes)
  ColliderShape s;
  if (child)
    s.type = n.required_choice<ShapeType>("type", {{"sphere", ShapeType::Sphere},
                                                   {"box", ShapeType::Box},
                                                   {"capsule", ShapeType::Capsule},
                                                   {"hull", ShapeType::Hull},
                                                   {"compound", ShapeType::Compound}});
  else
    s.type = n.required_choice<ShapeType>("type", {{"plane", ShapeType::Plane},
                                                   {"sphere", ShapeType::Sphere},
                                                   {"box", ShapeType::Box},
                                                   {"capsule", ShapeType::Capsule},
                                                   {"hull", ShapeType::Hull},
                                                   {"mesh", ShapeType::Mesh},
                                                   {"compound", ShapeType::Compound}});
  // shape fields belong to their types
  auto only_for = [&](const char* key, std::initializer_list<ShapeType> types, const char* names) {
    if (!n.has(key)) return;
    for (ShapeType t : types)
      if (s.type == t) return;
    n.at(key).fail(std::string("only for \"type\": ") + names);
  };
  only_for("normal", {ShapeType::Plane}, "\"plane\"");
  only_for("offset", {ShapeType::Plane}, "\"plane\"");
  only_for("radius", {ShapeType::Sphere, ShapeType::Capsule}, "\"sphere\" or \"capsule\"");
  only_for("half_extents", {ShapeType::Box}, "\"box\"");
  only_for("half_height", {ShapeType::Capsule}, "\"capsule\"");
  only_for("points", {ShapeType::Hull}, "\"hull\"");
  only_for("vertices", {ShapeType::Mesh}, "\"mesh\"");
  only_for("triangles", {ShapeType::Mesh}, "\"mesh\"");
  only_for("children", {ShapeType::Compound}, "\"compound\"");
  // the parameters
  switch (s.type) {
    case ShapeType::Plane:
      s.normal = n.nonzero_vec("normal", s.normal);
      s.offset = n.num("offset", s.offset);
      break;
    case ShapeType::Sphere: s.radius = n.float_positive("radius", s.radius); break;
    case ShapeType::Capsule:
      s.radius = n.float_positive("radius", s.radius);
      s.half_height = n.float_non_negative("half_height", s.half_height);
      break;
    case ShapeType::Box:
      if (n.has("half_extents")) {
        s.half_extents = n.at("half_extents").vec3();
        for (int i = 0; i < 3; ++i)
          if (!(s.half_extents[i] > 0))
            n.at("half_extents").item(i).fail("must be > 0, got " + format_value(s.half_extents[i]));
        require_float(s.half_extents, n.at("half_extents").where());
      }
      break;
    case ShapeType::Hull: s.hull = read_hull(n); break;
    case ShapeType::Mesh: s.mesh = read_mesh(n); break;
    case ShapeType::Compound: {
      // children at local poses, nested at most 8 deep
      if (depth >= 8) n.fail("compounds nest at most 8 deep");
      const Node ch = n.at("children");
      ch.require_array();
      if (ch.size() == 0) ch.fail("a compound needs at least one child, got 0");
      if (ch.size() > 4096) ch.fail("at most 4096 children, got " + std::to_string(ch.size()));
      std::vector<CompoundChild> children;
      for (std::size_t i = 0; i < ch.size(); ++i) {
        const Node c = ch.item(i);
        c.require_object();
        c.allow_only({"type", "position", "rotation", "rotation_deg", "radius", "half_extents", "half_height",
                      "points", "children"});
        children.push_back({read_shape(c, true, depth + 1), read_pose(c)});
      }
      try {
        s.compound = CompoundShape::build(std::move(children), "compound");
      } catch (const Error& e) {
        n.fail(e.what());  // the children were checked above: not expected
      }
      break;
    }
  }
  return s;
}

}  // namespace pba::scene_detail
