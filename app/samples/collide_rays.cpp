// "Collision/Ray casts": a fan of rays swept over a gallery of every collider shape
// (sphere, box, capsule, convex hull, triangle mesh, compound, ground plane); each ray is
// cast against every shape with pba::ray_cast and stops at the closest hit, whose point
// and surface normal are drawn. Click to cast a ray of your own from the camera. The
// "cast" option switches to the world queries (pba::QueryWorld over the same shapes): world
// ray casts, or sphere casts that draw the sphere where it first touches a shape.
#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include <imgui.h>

#include "camera.h"
#include "pba/collide/query.h"
#include "pba/collide/shape.h"
#include "renderer.h"
#include "sample.h"

namespace pba::app {
namespace {

constexpr Color kRay = Color::hex(0xffc53d, 0.55f);
constexpr Color kMiss = Color::hex(0x8a8f98, 0.25f);
constexpr Color kHit = colors::yellow;
constexpr Color kNormal = colors::cyan;
constexpr Color kClick = colors::pink;
constexpr Color kShape = Color::hex(0x3e63dd, 0.85f);

struct Placed {
  ColliderShape shape;
  Pose pose;
  const char* name;
};

class CollideRays final : public Sample {
 public:
  explicit CollideRays(SampleContext& ctx) : Sample(ctx) {
    ctx.camera->frame({0.2f, 0.45f, 0.2f}, 4.4f, 0.0f, 0.5f);
    const std::string cast = ctx.option("cast", "shapes");
    if (cast == "shapes") mode_ = kShapeByShape;
    else if (cast == "rays") mode_ = kWorldRays;
    else if (cast == "spheres") mode_ = kSphereCasts;
    else throw Error("--option cast=" + cast + ": expected shapes, rays or spheres");
    const std::string rays = ctx.option("rays", "40");
    rays_ = std::atoi(rays.c_str());
    if (rays_ < 1 || rays_ > 100 || rays.find_first_not_of("0123456789") != std::string::npos)
      throw Error("--option rays=" + rays + ": expected a count in [1, 100]");
    const std::string radius = ctx.option("radius", "0.12");
    char* end = nullptr;
    radius_ = std::strtof(radius.c_str(), &end);
    if (end == radius.c_str() || *end != 0 || !(radius_ >= 0.02f && radius_ <= 0.4f))
      throw Error("--option radius=" + radius + ": expected a sphere radius in [0.02, 0.4] m");
    build_gallery();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<CollideRays>(ctx); }

  // the fan turns slowly so every frame differs
  void Step(double, double dt) override {
    if (spin_) angle_ += 0.35 * dt;
  }

  void Draw(Renderer& r, double) override {
    hits_ = 0;
    for (const Placed& p : shapes_) draw_shape(r, p);
    // the fan: from a point above and in front of the gallery, aimed at three rows of
    // targets across it that sway with the sweep
    const Vec3 origin(1.2 * std::sin(0.7 * angle_), 2.6, 3.6);
    for (int row = 0; row < 3; ++row)
      for (int i = 0; i < rays_; ++i) {
        const double u = rays_ == 1 ? 0.5 : double(i) / (rays_ - 1);
        const Vec3 target(spread_ * (u - 0.5) + 0.4 * std::sin(angle_ + 0.5 * row), 0.15 + 0.35 * row,
                          0.3 * std::cos(2 * angle_ + 3 * u));
        cast_and_draw(r, Ray{origin, glm::normalize(target - origin), 12.0}, kRay, kMiss);
      }    r.point(origin, 9.0f, colors::white);
    if (clicked_) cast_and_draw(r, click_, kClick, kClick);
  }

  void Mouse(int button, bool down, const Vec3& o, const Vec3& d) override {
    if (button != 0 || !down) return;
    click_ = Ray{o, glm::normalize(d), 100.0};
    clicked_ = true;
  }

  void DrawUI() override {
    if (mode_ == kShapeByShape)
      ImGui::TextWrapped("Each ray is cast against every shape (pba::ray_cast) and stops at the "
                         "closest hit: the yellow point, with the surface normal in cyan. Click "
                         "anywhere to cast a ray from the camera (pink).");
    else if (mode_ == kWorldRays)
      ImGui::TextWrapped("Each ray is one QueryWorld::ray_cast over all the shapes (a tree of their "
                         "bounds): the closest hit in yellow, its normal in cyan. Click to cast one.");
    else
      ImGui::TextWrapped("Each ray is the path of a sphere's centre (QueryWorld::sphere_cast): the "
                         "sphere is drawn where it first touches a shape, the contact point in "
                         "yellow and the surface normal in cyan. Click to cast one.");
    ImGui::SliderInt("rays per row", &rays_, 1, 100);
    ImGui::SliderFloat("spread (m)", &spread_, 0.5f, 9.0f);
    ImGui::Checkbox("sweep", &spin_);
    ImGui::Combo("cast", &mode_, "shape by shape (ray_cast)\0world rays (QueryWorld)\0sphere casts (QueryWorld)\0");
    if (mode_ == kSphereCasts) ImGui::SliderFloat("sphere radius (m)", &radius_, 0.02f, 0.4f);
    ImGui::Text("hits this frame: %d of %d", hits_, 3 * rays_);
    if (clicked_ && click_hit_.hit)
      ImGui::Text("click: %s at %.3f m, feature %u", click_name_.c_str(), click_hit_.distance, click_hit_.feature);
  }

  std::vector<Color> ExpectedColors() const override { return {kHit}; }

 private:
  void build_gallery() {
    // a rock: the hull of a squashed random-looking cloud (fixed, so frames are reproducible)
    std::vector<Vec3> rock;
    for (int i = 0; i < 40; ++i) {
      const double t = 2.399963 * i, z = 1 - 2 * (i + 0.5) / 40, s = std::sqrt(1 - z * z);
      const double bump = 0.8 + 0.2 * std::sin(5.0 * i);
      rock.push_back(bump * Vec3(0.55 * s * std::cos(t), 0.4 * z, 0.45 * s * std::sin(t)));
    }
    // a bowl of triangles
    std::vector<Vec3> v;
    std::vector<std::array<std::uint32_t, 3>> tris;
    const int n = 10;
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n; ++j) {
        const double x = 1.4 * (double(i) / n - 0.5), z = 1.4 * (double(j) / n - 0.5);
        v.push_back(Vec3(x, 0.5 * (x * x + z * z), z));
      }
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const auto id = [&](int a, int b) { return static_cast<std::uint32_t>(a * (n + 1) + b); };
        tris.push_back({id(i, j), id(i, j + 1), id(i + 1, j)});
        tris.push_back({id(i + 1, j), id(i, j + 1), id(i + 1, j + 1)});
      }
    // a table: a top and four legs
    const ColliderShape leg = ColliderShape::capsule(0.22, 0.05);
    std::vector<CompoundChild> table = {{ColliderShape::box({0.45, 0.05, 0.3}), Pose{{0, 0.3, 0}, {1, 0, 0, 0}}}};
    for (double sx : {-0.38, 0.38})
      for (double sz : {-0.23, 0.23}) table.push_back({leg, Pose{{sx, 0.0, sz}, {1, 0, 0, 0}}});
    ColliderShape compound;
    compound.type = ShapeType::Compound;
    compound.compound = CompoundShape::build(std::move(table), "table");

    const Quat tilt = glm::angleAxis(0.5, glm::normalize(Vec3(1, 0.3, 0.2)));
    shapes_ = {
        {ColliderShape::plane({0, 1, 0}, 0), Pose{}, "ground"},
        {ColliderShape::sphere(0.45), Pose{{-3.0, 0.45, 0}, {1, 0, 0, 0}}, "sphere"},
        {ColliderShape::box({0.35, 0.3, 0.45}), Pose{{-1.8, 0.5, 0.2}, tilt}, "box"},
        {ColliderShape::capsule(0.35, 0.22), Pose{{-0.6, 0.6, -0.1}, glm::angleAxis(1.1, Vec3(0, 0, 1))}, "capsule"},
        {ColliderShape::convex(ConvexHull::build(rock, "rock")), Pose{{0.6, 0.45, 0.1}, tilt}, "hull"},
        {ColliderShape::triangles(TriangleMesh::build(v, tris, "bowl")), Pose{{1.9, 0.05, 0}, {1, 0, 0, 0}}, "mesh"},
        {compound, Pose{{3.2, 0.3, 0}, glm::angleAxis(0.4, Vec3(0, 1, 0))}, "compound"},
    };
    // the same shapes as a query world
    std::vector<Collider> colliders;
    for (const Placed& p : shapes_) {
      Collider c;
      c.shape = p.shape;
      c.begin = c.end = p.pose;
      colliders.push_back(c);
    }
    queries_.build(colliders);
  }

  // the closest hit over the gallery, shape by shape or through the query world; draws the
  // ray, and the hit point and normal (a sphere cast: the sphere at its first contact)
  void cast_and_draw(Renderer& r, const Ray& ray, Color ray_color, Color miss_color) {
    RayHit best;
    std::size_t which = 0;
    if (mode_ == kShapeByShape) {
      for (std::size_t i = 0; i < shapes_.size(); ++i) {
        const RayHit h = ray_cast(shapes_[i].shape, shapes_[i].pose, ray);
        if (h.hit && (!best.hit || h.distance < best.distance)) best = h, which = i;
      }
    } else if (mode_ == kWorldRays) {
      const QueryRayHit h = queries_.ray_cast(ray);
      best = {h.hit, h.distance, h.point, h.normal, h.feature};
      which = h.collider;
    } else {
      const ShapeCastHit h = queries_.sphere_cast(ray, radius_);
      best = {h.hit, h.distance, h.point, h.normal, 0};
      which = h.collider;
      if (h.hit) r.sphere(ray.origin + h.distance * ray.direction, radius_, Color::hex(0xffc53d, 0.35f));
    }
    if (&ray == &click_) click_hit_ = best, click_name_ = best.hit ? shapes_[which].name : "";
    else hits_ += best.hit;
    if (!best.hit) {
      r.line(ray.origin, ray.origin + ray.max_distance * ray.direction, miss_color);
      return;
    }
    r.line(ray.origin, best.point, ray_color);
    r.point(best.point, 7.0f, &ray == &click_ ? kClick : kHit);
    r.arrow(best.point, best.point + 0.25 * best.normal, 0.06, kNormal);
  }

  void draw_shape(Renderer& r, const Placed& p) const {
    const ColliderShape& s = p.shape;
    switch (s.type) {
      case ShapeType::Plane: r.plane(s.normal, s.offset, 4.5, Color::hex(0x8a8f98, 0.25f)); break;
      case ShapeType::Sphere: r.sphere(p.pose.position, s.radius, kShape); break;
      case ShapeType::Box: r.box(p.pose.position, s.half_extents, p.pose.rotation, kShape); break;
      case ShapeType::Capsule:
        r.capsule(apply(p.pose, Vec3(0, -s.half_height, 0)), apply(p.pose, Vec3(0, s.half_height, 0)), s.radius, kShape);
        break;
      case ShapeType::Hull: {
        // each face as a fan, its edges drawn over it
        const auto e = s.hull->edges();
        const auto v = s.hull->vertices();
        for (const auto& f : s.hull->faces()) {
          const Vec3 a = apply(p.pose, v[e[f.edge].origin]);
          for (std::uint32_t i = e[f.edge].next; e[i].next != f.edge; i = e[i].next)
            r.triangle(a, apply(p.pose, v[e[i].origin]), apply(p.pose, v[e[e[i].next].origin]), kShape);
        }
        for (std::size_t i = 0; i < e.size(); i += 2)
          r.line(apply(p.pose, v[e[i].origin]), apply(p.pose, v[e[i + 1].origin]), Color::hex(0xffffff, 0.35f));
        break;
      }
      case ShapeType::Mesh: {
        const auto v = s.mesh->vertices();
        for (const auto& t : s.mesh->triangles()) {
          const Vec3 a = apply(p.pose, v[t[0]]), b = apply(p.pose, v[t[1]]), c = apply(p.pose, v[t[2]]);
          r.triangle(a, b, c, Color::hex(0x46a758, 0.85f));  // lit on both sides
          r.line(a, b, Color::hex(0xffffff, 0.3f));
        }
        break;
      }
      case ShapeType::Compound:
        for (const CompoundChild& c : s.compound->children) draw_shape(r, {c.shape, compose(p.pose, c.pose), p.name});
        break;
    }
  }

  enum Mode { kShapeByShape, kWorldRays, kSphereCasts };
  std::vector<Placed> shapes_;
  QueryWorld queries_;
  int mode_ = kShapeByShape;
  float radius_ = 0.12f;
  double angle_ = 0;
  int rays_ = 40;
  float spread_ = 7.6f;
  bool spin_ = true;
  int hits_ = 0;
  Ray click_{};
  bool clicked_ = false;
  RayHit click_hit_{};
  std::string click_name_;
};

static int reg = RegisterSample("Collision", "Ray casts", CollideRays::Create);

}  // namespace
}  // namespace pba::app
