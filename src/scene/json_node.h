// Private to the scene reader: a JSON value that knows where it is (Node), and the
// readers of the fields several modules share. Every value is read through a Node that
// knows its JSON pointer (RFC 6901), so every error names the file, the path of the bad
// field and what is wrong with it. Unknown fields are errors too (a typo must not be
// silently ignored). nlohmann::json stays in src/scene/.
#pragma once

#include <cmath>
#include <initializer_list>
#include <map>
#include <string>
#include <string_view>
#include <utility>

#include <nlohmann/json.hpp>

#include "pba/scene.h"

namespace pba::scene_detail {

using json = nlohmann::json;

// the file name that prefixes every message, and the entity names the file has given so far
// (each with the path of the entity that took it)
struct Context {
  std::string source;
  mutable std::map<std::string, std::string, std::less<>> names;
};

// a JSON value and where it is
class Node {
 public:
  Node(const json& j, std::string path, const Context& ctx) : j_(j), path_(std::move(path)), ctx_(ctx) {}

  const std::string& path() const { return path_; }
  const json& raw() const { return j_; }
  [[noreturn]] void fail(const std::string& what) const {
    throw Error(ctx_.source + ": " + (path_.empty() ? "/" : path_) + ": " + what);
  }
  // the message prefix for library validation of this node
  std::string where() const { return ctx_.source + ": " + (path_.empty() ? "/" : path_); }

  // ---- structure ----
  void require_object() const {
    if (!j_.is_object()) fail("must be an object, got " + type_name(j_));
  }
  void require_array() const {
    if (!j_.is_array()) fail("must be an array, got " + type_name(j_));
  }
  // unknown fields are errors: list what is allowed
  void allow_only(std::initializer_list<const char*> keys) const {
    require_object();
    for (auto it = j_.begin(); it != j_.end(); ++it) {
      bool ok = false;
      for (const char* k : keys) ok |= it.key() == k;
      if (ok) continue;
      std::string list;
      for (const char* k : keys) list += (list.empty() ? "" : ", ") + std::string(k);
      Node(it.value(), child_path(it.key()), ctx_).fail("unknown field (allowed here: " + list + ")");
    }
  }
  bool has(const char* key) const { return j_.is_object() && j_.contains(key); }
  // this entity's "name" (empty when none): two entities of a file may not share one, as the
  // CSV's body column and World::find tell entities by it
  std::string entity_name() const {
    std::string name = str("name", "");
    if (name.empty()) return name;
    const auto [it, fresh] = ctx_.names.try_emplace(name, path_);
    if (!fresh)
      at("name").fail("\"" + name + "\" is already the name of " + it->second + " (entity names must be unique)");
    return name;
  }
  Node at(const char* key) const {
    if (!has(key)) fail(std::string("missing required field \"") + key + "\"");
    return Node(j_.at(key), child_path(key), ctx_);
  }
  Node item(std::size_t i) const { return Node(j_.at(i), path_ + "/" + std::to_string(i), ctx_); }
  std::size_t size() const { return j_.size(); }

  // ---- leaves ----
  double number() const {
    if (!j_.is_number()) fail("must be a number, got " + type_name(j_));
    const double v = j_.get<double>();
    if (!std::isfinite(v)) fail("must be a finite number, got " + format_value(v));
    return v;
  }
  std::string string() const {
    if (!j_.is_string()) fail("must be a string, got " + type_name(j_));
    return j_.get<std::string>();
  }
  bool boolean() const {
    if (!j_.is_boolean()) fail("must be true or false, got " + type_name(j_));
    return j_.get<bool>();
  }
  Vec3 vec3() const {
    if (!j_.is_array() || j_.size() != 3) fail("must be an array of 3 numbers, got " + type_name(j_));
    return {item(0).number(), item(1).number(), item(2).number()};
  }
  long long integer(long long lo, long long hi) const {
    if (!j_.is_number_integer() && !j_.is_number_unsigned()) fail("must be an integer, got " + type_name(j_));
    const long long v = j_.is_number_unsigned() ? static_cast<long long>(j_.get<unsigned long long>())
                                                : j_.get<long long>();
    if (v < lo || v > hi)
      fail("must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
           std::to_string(v));
    return v;
  }

  // ---- optional fields with range checks ----
  double num(const char* key, double def) const { return has(key) ? at(key).number() : def; }
  double positive(const char* key, double def) const {
    const double v = num(key, def);
    if (!(v > 0)) at(key).fail("must be > 0, got " + format_value(v));
    return v;
  }
  double non_negative(const char* key, double def) const {
    const double v = num(key, def);
    if (!(v >= 0)) at(key).fail("must be >= 0, got " + format_value(v));
    return v;
  }
  double in_range(const char* key, double lo, double hi, double def) const {
    const double v = num(key, def);
    if (!(v >= lo && v <= hi))
      at(key).fail("must be in [" + format_value(lo) + ", " + format_value(hi) + "], got " + format_value(v));
    return v;
  }
  Vec3 vec(const char* key, const Vec3& def) const { return has(key) ? at(key).vec3() : def; }
  Vec3 nonzero_vec(const char* key, const Vec3& def) const {
    const Vec3 v = vec(key, def);
    if (v == Vec3(0)) at(key).fail("must be a non-zero vector, got (0, 0, 0)");
    if (glm::length(v) == 0) at(key).fail("is too short to normalise (its length underflows), got " + format_vec3(v));
    return v;
  }
  // values stored as float: finite as a float too (Error names the path)
  Vec3 float_vec(const char* key, const Vec3& def) const {
    const Vec3 v = vec(key, def);
    if (has(key)) require_float(v, at(key).where());
    return v;
  }
  double float_positive(const char* key, double def) const {
    const double v = positive(key, def);
    if (has(key)) require_float(v, at(key).where());
    return v;
  }
  double float_non_negative(const char* key, double def) const {
    const double v = non_negative(key, def);
    if (has(key)) require_float(v, at(key).where());
    return v;
  }
  // a mass stored as its float inverse
  double mass(const char* key, double def) const {
    const double v = positive(key, def);
    if (has(key)) require_float_inverse(v, at(key).where());
    return v;
  }
  // the path of a field, given or not (for limits that several fields decide)
  std::string where(const char* key) const { return where() + "/" + pointer_token(key); }
  bool flag(const char* key, bool def) const { return has(key) ? at(key).boolean() : def; }
  std::string str(const char* key, const std::string& def) const { return has(key) ? at(key).string() : def; }
  // one of a fixed set of names
  template <class E>
  E choice(const char* key, std::initializer_list<std::pair<const char*, E>> options, E def) const {
    if (!has(key)) return def;
    const std::string s = at(key).string();
    std::string list;
    for (const auto& [name, value] : options) {
      if (s == name) return value;
      list += (list.empty() ? "\"" : ", \"") + std::string(name) + "\"";
    }
    at(key).fail("unknown value \"" + s + "\" (expected one of " + list + ")");
  }
  template <class E>
  E required_choice(const char* key, std::initializer_list<std::pair<const char*, E>> options) const {
    at(key);  // missing -> error
    return choice(key, options, options.begin()->second);
  }

  /// A key as a JSON pointer token (RFC 6901): ~ becomes ~0, / becomes ~1.
  static std::string pointer_token(std::string_view key) {
    std::string k;
    for (char c : key) {
      if (c == '~')
        k += "~0";
      else if (c == '/')
        k += "~1";
      else
        k += c;
    }
    return k;
  }

  static std::string type_name(const json& j) {
    if (j.is_null()) return "null";
    if (j.is_boolean()) return j.get<bool>() ? "true" : "false";
    if (j.is_number()) return "the number " + format_value(j.get<double>());
    if (j.is_string()) return "the string \"" + j.get<std::string>() + "\"";
    if (j.is_array()) return "an array of " + std::to_string(j.size());
    return "an object";
  }

 private:
  std::string child_path(const std::string& key) const { return path_ + "/" + pointer_token(key); }

  const json& j_;
  std::string path_;
  const Context& ctx_;
};

// ---- shared field readers (read_world.cpp) ----

/// A rotation: "rotation_deg": [x, y, z] (applied about X, then Y, then Z) or
/// "rotation": [w, x, y, z] (normalised; must be non-zero); identity when neither is given.
Quat read_rotation(const Node& n);
/// "position" and the rotation of an entity-like item.
Pose read_pose(const Node& n);
/// A colour: "#rrggbb", "#rrggbbaa" or [r, g, b] / [r, g, b, a] in [0, 1]; `def` when absent.
Color read_color(const Node& n, const char* key, Color def);
/// An integrator name (the integrate module's message lists the valid names).
Method read_method(const Node& m);
/// A new entity with the item's "name" and pose.
EntityId make_entity(const Node& n, World& w);
/// The fields every entity-like item may have (a "kinematic" path).
void read_common(const Node& n, World& w, EntityId e);

// ---- one reader per module: the settings, and one item of each top-level array ----

/// "settings": the step, the integrator and the particles' forces (read_world.cpp).
void read_settings(const Node& n, WorldDef& def);
/// One item of "colliders" (read_world.cpp).
void read_collider(const Node& n, World& w);
/// A collider's shape: its "type" and that type's fields (read_shapes.cpp). A compound's
/// child (`child`) is a sphere, box, capsule, hull or compound, nested `depth` deep.
ColliderShape read_shape(const Node& n, bool child, int depth);
/// One item of "particles" (read_particles.cpp).
void read_particle(const Node& n, World& w);
/// One item of "emitters" (read_particles.cpp).
void read_emitter(const Node& n, World& w);
/// One item of "forcers" (read_particles.cpp).
void read_forcer(const Node& n, World& w);
/// One item of "soft_bodies" (read_soft.cpp).
void read_soft_body(const Node& n, World& w);
/// "settings.rigid": the rigid bodies' solver and contact settings (read_rigid.cpp).
void read_rigid_settings(const Node& n, RigidSystemDef& def);
/// One item of "rigid_bodies" (read_rigid.cpp).
void read_rigid_body(const Node& n, World& w);

}  // namespace pba::scene_detail
