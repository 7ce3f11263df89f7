// Soft bodies: validation, the generic mesh builder (graph colouring and runs), pins and
// grabbing, tearing, collisions, queries and drawing. The solvers are in xpbd.cpp and
// mass_spring.cpp; the builders of springs, ropes, cloth and jelly in builders.cpp.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <unordered_map>

#include "core/squarable.h"
#include "pba/particles.h"
#include "soft_impl.h"

namespace pba {

namespace {

std::string idx(std::string_view where, std::string_view field, std::size_t i) {
  return std::string(where) + "." + std::string(field) + "[" + std::to_string(i) + "]";
}

// throws Error "<where>: must be finite and >= 0, got v" unless v is
void non_negative(double v, std::string_view where, std::string_view name) {
  if (!(std::isfinite(v) && v >= 0)) require_non_negative(v, field_path(where, name));
}

// Collider::validate's checks without building any message (it runs every step and must
// not allocate); when this fails, validate() reports the failure by name.
double tet_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return glm::dot(glm::cross(b - a, c - a), d - a) / 6.0;
}

}  // namespace

// ---------------------------------------------------------------------------------------
// settings

void SoftBodyDef::validate(std::string_view where) const {
  // solver and counts
  if (solver != SoftSolver::MassSpring && solver != SoftSolver::Xpbd)
    throw Error(field_path(where, "solver") + ": unknown solver " + std::to_string(static_cast<int>(solver)));
  if (static_cast<int>(method) < 0 || static_cast<int>(method) > static_cast<int>(Method::ImplicitEuler))
    throw Error(field_path(where, "method") + ": unknown method " + std::to_string(static_cast<int>(method)));
  // (every check builds its message only when it fails: validation runs each step and
  // must not allocate)
  if (substeps < 1 || substeps > 10000) require_count(substeps, 1, 10000, field_path(where, "substeps"));
  if (iterations < 1 || iterations > 1000) require_count(iterations, 1, 1000, field_path(where, "iterations"));
  // compliances, stiffnesses and damping
  non_negative(stretch_compliance, where, "stretch_compliance");
  non_negative(shear_compliance, where, "shear_compliance");
  non_negative(bend_compliance, where, "bend_compliance");
  non_negative(volume_compliance, where, "volume_compliance");
  non_negative(stretch_stiffness, where, "stretch_stiffness");
  non_negative(shear_stiffness, where, "shear_stiffness");
  non_negative(bend_stiffness, where, "bend_stiffness");
  non_negative(volume_stiffness, where, "volume_stiffness");
  non_negative(spring_damping, where, "spring_damping");
  // forces, aerodynamics, tearing, collisions
  try {
    forces.validate("forces");
  } catch (const Error&) {
    forces.validate(field_path(where, "forces"));  // the same failure, with the full path
  }
  non_negative(aero.air_density, where, "aero.air_density");
  non_negative(aero.drag, where, "aero.drag");
  non_negative(aero.lift, where, "aero.lift");
  non_negative(tear_strain, where, "tear_strain");
  non_negative(thickness, where, "thickness");  // (its bound depends on the substep: step)
  non_negative(friction, where, "friction");
  non_negative(damping, where, "damping");
}

// ---------------------------------------------------------------------------------------
// construction

SoftBody::SoftBody() : impl_(std::make_unique<Impl>()) {}
SoftBody::SoftBody(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SoftBody::~SoftBody() = default;
SoftBody::SoftBody(SoftBody&&) noexcept = default;
SoftBody& SoftBody::operator=(SoftBody&&) noexcept = default;

namespace {

// Greedy graph colouring of the constraints (Welsh & Powell 1967 without the degree
// ordering): each constraint takes the smallest colour neither particle has yet, so at
// most 2 (max degree) - 1 colours. Deterministic: constraints in the given order.
std::vector<std::uint32_t> greedy_colors(const SoftMesh& m) {
  const std::size_t n = m.positions.size();
  // degree bounds the number of colours and so the bitset width
  std::vector<std::uint32_t> degree(n, 0);
  for (const auto& c : m.constraints) {
    ++degree[c.a];
    ++degree[c.b];
  }
  const std::uint32_t max_deg = n ? *std::max_element(degree.begin(), degree.end()) : 0;
  const std::size_t words = (2 * static_cast<std::size_t>(max_deg)) / 64 + 1;
  std::vector<std::uint64_t> used(n * words, 0);
  std::vector<std::uint32_t> color(m.constraints.size(), 0);
  for (std::size_t k = 0; k < m.constraints.size(); ++k) {
    const std::uint64_t* ua = &used[m.constraints[k].a * words];
    const std::uint64_t* ub = &used[m.constraints[k].b * words];
    // the first colour free at both ends
    std::uint32_t c = 0;
    for (std::size_t wd = 0; wd < words; ++wd) {
      const std::uint64_t free_bits = ~(ua[wd] | ub[wd]);
      if (free_bits) {
        c = static_cast<std::uint32_t>(wd * 64 + static_cast<std::size_t>(__builtin_ctzll(free_bits)));
        break;
      }
    }
    color[k] = c;
    used[m.constraints[k].a * words + c / 64] |= 1ULL << (c % 64);
    used[m.constraints[k].b * words + c / 64] |= 1ULL << (c % 64);
  }
  return color;
}

// Splits one colour's constraints (sorted by kind, offset, a) into runs: contiguous where
// a steps by 1, interleaved where a follows a0, .., a0+L-1, a0+2L, .. with b = a + L,
// and indexed for the rest. Runs shorter than kMinRun go to indexed runs.
void make_runs(std::uint32_t c_begin, std::uint32_t c_end, std::uint32_t color, const std::vector<std::uint32_t>& ca,
               const std::vector<std::uint32_t>& cb, const std::vector<std::uint8_t>& kind,
               std::vector<detail::Run>& runs) {
  constexpr std::uint32_t kMinRun = 4;
  std::uint32_t i = c_begin;
  auto same_group = [&](std::uint32_t j, std::uint32_t k) {
    return kind[j] == kind[k] && cb[j] - ca[j] == cb[k] - ca[k];
  };
  auto push_indexed = [&](std::uint32_t c) {
    // extend the previous indexed run when it ends here with the same kind
    if (!runs.empty() && runs.back().type == detail::RunType::Indexed && runs.back().c0 + runs.back().count == c &&
        static_cast<std::uint8_t>(runs.back().kind) == kind[c] && runs.back().color == color) {
      ++runs.back().count;
      return;
    }
    runs.push_back({.c0 = c, .count = 1, .a0 = ca[c], .type = detail::RunType::Indexed,
                    .kind = static_cast<SoftConstraintKind>(kind[c]), .color = color});
  };
  while (i < c_end) {
    const std::uint32_t off = cb[i] - ca[i];
    // contiguous length
    std::uint32_t m1 = 1;
    while (i + m1 < c_end && same_group(i, i + m1) && ca[i + m1] == ca[i] + m1) ++m1;
    if (m1 >= kMinRun) {
      runs.push_back({.c0 = i, .count = m1, .a0 = ca[i], .offset = off, .type = detail::RunType::Contiguous,
                      .kind = static_cast<SoftConstraintKind>(kind[i]), .color = color});
      i += m1;
      continue;
    }
    // interleaved length with L = offset in {1, 2}
    if (off == 1 || off == 2) {
      std::uint32_t m2 = 1;
      while (i + m2 < c_end && same_group(i, i + m2) && ca[i + m2] == ca[i] + (m2 / off) * 2 * off + m2 % off)
        ++m2;
      m2 -= m2 % off;  // whole groups only
      if (m2 >= kMinRun) {
        runs.push_back({.c0 = i, .count = m2, .a0 = ca[i], .offset = off, .type = detail::RunType::Interleaved,
                        .kind = static_cast<SoftConstraintKind>(kind[i]), .color = color});
        i += m2;
        continue;
      }
    }
    push_indexed(i);
    ++i;
  }
}

}  // namespace

SoftBody SoftBody::from_mesh(const SoftMesh& m, const SoftBodyDef& def, std::string_view where) {
  // settings and sizes
  def.validate("SoftBodyDef");
  const std::size_t n = m.positions.size();
  if (n == 0) throw Error(field_path(where, "positions") + ": must hold at least 1 particle, got 0");
  if (n >= kNoParticle) throw Error(field_path(where, "positions") + ": too many particles");
  if (m.masses.size() != n)
    throw Error(field_path(where, "masses") + ": must have one mass per particle (" + std::to_string(n) + "), got " +
                std::to_string(m.masses.size()));
  if (!m.velocities.empty() && m.velocities.size() != n)
    throw Error(field_path(where, "velocities") + ": must be empty or have one per particle (" +
                std::to_string(n) + "), got " + std::to_string(m.velocities.size()));
  if (!m.colors.empty() && m.colors.size() != m.constraints.size())
    throw Error(field_path(where, "colors") + ": must be empty or have one per constraint (" +
                std::to_string(m.constraints.size()) + "), got " + std::to_string(m.colors.size()));
  // particles
  // the state is float columns: positions, velocities and inverse masses must fit a float
  for (std::size_t i = 0; i < n; ++i) {
    if (!fits_float(m.positions[i])) require_float(m.positions[i], idx(where, "positions", i));
    if (!(std::isfinite(m.masses[i]) && m.masses[i] > 0)) require_positive(m.masses[i], idx(where, "masses", i));
    if (!std::isnormal(static_cast<float>(1 / m.masses[i])))
      require_float_inverse(m.masses[i], idx(where, "masses", i));
    if (!m.velocities.empty() && !fits_float(m.velocities[i]))
      require_float(m.velocities[i], idx(where, "velocities", i));
  }
  auto check_index = [&](std::uint32_t p, std::string_view field, std::size_t k, std::string_view end) {
    if (p >= n)
      throw Error(idx(where, field, k) + "." + std::string(end) + ": particle " + std::to_string(p) +
                  " does not exist (the mesh has " + std::to_string(n) + " particles)");
  };
  // constraints: indices, distinct ends, rest lengths (a normal float whose square is finite)
  const double kMaxLength = detail::squarable_hi<float>();
  std::vector<SoftConstraint> cons = m.constraints;
  for (std::size_t k = 0; k < cons.size(); ++k) {
    SoftConstraint& c = cons[k];
    check_index(c.a, "constraints", k, "a");
    check_index(c.b, "constraints", k, "b");
    if (c.a == c.b)
      throw Error(idx(where, "constraints", k) + ": joins particle " + std::to_string(c.a) + " to itself");
    if (static_cast<int>(c.kind) > static_cast<int>(SoftConstraintKind::Bend))
      throw Error(idx(where, "constraints", k) + ".kind: unknown kind " + std::to_string(static_cast<int>(c.kind)));
    if (!std::isfinite(c.rest_length)) require_finite(c.rest_length, idx(where, "constraints", k) + ".rest_length");
    if (c.rest_length < 0) {
      c.rest_length = glm::length(m.positions[c.b] - m.positions[c.a]);
      if (!(c.rest_length > 0))
        throw Error(idx(where, "constraints", k) + ".rest_length: zero rest length between coincident particles " +
                    std::to_string(c.a) + " and " + std::to_string(c.b) + " at " + format_vec3(m.positions[c.a]));
    } else if (!(c.rest_length > 0)) {
      throw Error(idx(where, "constraints", k) + ".rest_length: must be > 0, got " + format_value(c.rest_length));
    }
    // the solver keeps rest lengths in float and squares lengths in float
    if (!detail::squarable<float>(c.rest_length))
      detail::throw_not_squarable<float>(c.rest_length, idx(where, "constraints", k) + ".rest_length", "m",
                                         "kept in float, and squared");
    if (const double d = glm::length(m.positions[c.b] - m.positions[c.a]); !(d <= kMaxLength))
      throw Error(idx(where, "constraints", k) + ": particles " + std::to_string(c.a) + " and " +
                  std::to_string(c.b) + " are " + format_value(d) + " m apart, more than " +
                  format_value(kMaxLength) + " m (the solver squares lengths in float)");
    if (c.a > c.b) std::swap(c.a, c.b);  // a < b, so runs have positive offsets
  }
  // triangles and tetrahedra
  for (std::size_t k = 0; k < m.triangles.size(); ++k) {
    const SoftTriangle& t = m.triangles[k];
    check_index(t.a, "triangles", k, "a");
    check_index(t.b, "triangles", k, "b");
    check_index(t.c, "triangles", k, "c");
    if (t.a == t.b || t.b == t.c || t.a == t.c)
      throw Error(idx(where, "triangles", k) + ": repeats a particle (" + std::to_string(t.a) + ", " +
                  std::to_string(t.b) + ", " + std::to_string(t.c) + ")");
  }
  std::vector<SoftTet> tets = m.tets;
  std::vector<float> tet_rest(tets.size());
  double rest_volume = 0;
  for (std::size_t k = 0; k < tets.size(); ++k) {
    SoftTet& t = tets[k];
    check_index(t.a, "tets", k, "a");
    check_index(t.b, "tets", k, "b");
    check_index(t.c, "tets", k, "c");
    check_index(t.d, "tets", k, "d");
    double v = tet_volume(m.positions[t.a], m.positions[t.b], m.positions[t.c], m.positions[t.d]);
    if (!(std::abs(v) > 0))
      throw Error(idx(where, "tets", k) + ": zero rest volume (particles " + std::to_string(t.a) + ", " +
                  std::to_string(t.b) + ", " + std::to_string(t.c) + ", " + std::to_string(t.d) + " are coplanar)");
    // the volume solve forms sum_j w_j |grad_j|^2 (grad ~ an edge squared) in float: at
    // rest it must fit 16 times over, room for the edges to stretch 2x (a 1e12 m jelly's
    // overflowed at the first step, and the state turned NaN)
    {
      const Vec3 e1 = m.positions[t.b] - m.positions[t.a], e2 = m.positions[t.c] - m.positions[t.a],
                 e3 = m.positions[t.d] - m.positions[t.a];
      const Vec3 g1 = glm::cross(e2, e3), g2 = glm::cross(e3, e1), g3 = glm::cross(e1, e2), g0 = -(g1 + g2 + g3);
      // each |grad|^2 (an edge to the fourth) is formed in float before the masses divide
      // it: 1e10 m edges overflowed with 1e12 kg particles, the sum below fitted, and the
      // volume constraint silently did nothing (a correction of 0 / inf)
      const Vec3 gs[4] = {g0, g1, g2, g3};
      const std::uint32_t ids[4] = {t.a, t.b, t.c, t.d};
      for (int j = 0; j < 4; ++j)
        if (const double gg = glm::dot(gs[j], gs[j]); !(16 * gg <= std::numeric_limits<float>::max()))
          throw Error(idx(where, "tets", k) + ": too large for the float volume solve: |grad V|^2 at its particle " +
                      std::to_string(ids[j]) + " is " + format_value(gg) +
                      " m^4 at rest, over 1/16 of the largest float (room for a 2x stretch); use smaller "
                      "tetrahedra (heavier particles do not help: the square is formed before the mass divides it)");
      const double den = glm::dot(g0, g0) / m.masses[t.a] + glm::dot(g1, g1) / m.masses[t.b] +
                         glm::dot(g2, g2) / m.masses[t.c] + glm::dot(g3, g3) / m.masses[t.d];
      if (!(16 * den <= std::numeric_limits<float>::max()))
        throw Error(idx(where, "tets", k) + ": too large for the float volume solve: sum of |grad V|^2 / mass over "
                    "its particles is " + format_value(den) + " m^4/kg at rest, over 1/16 of the largest float (" +
                    "room for a 2x stretch); use smaller tetrahedra or heavier particles");
    }
    // positive orientation
    if (v < 0) {
      std::swap(t.c, t.d);
      v = -v;
    }
    tet_rest[k] = static_cast<float>(v);
    rest_volume += v;
  }
  for (std::size_t k = 0; k < m.pinned.size(); ++k) check_index(m.pinned[k], "pinned", k, "index");

  // colours: given (checked) or greedy (its bitsets hold 2 x the largest degree per
  // particle, so a hub with thousands of constraints is refused rather than using GBs)
  if (m.colors.empty()) {
    std::vector<std::uint32_t> degree(n, 0);
    for (const SoftConstraint& c : cons) ++degree[c.a], ++degree[c.b];
    for (std::size_t i = 0; i < n; ++i)
      if (degree[i] > 4096)
        throw Error(field_path(where, "constraints") + ": particle " + std::to_string(i) + " is in " +
                    std::to_string(degree[i]) + " constraints; at most 4096 per particle");
  }
  std::vector<std::uint32_t> color = m.colors.empty() ? greedy_colors(m) : m.colors;
  const std::uint32_t n_colors = cons.empty() ? 0 : *std::max_element(color.begin(), color.end()) + 1;
  if (n_colors > 1u << 16) throw Error(field_path(where, "colors") + ": more than 65536 colours");
  // solver order: by colour, then kind, then offset b - a, then a
  std::vector<std::uint32_t> order(cons.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](std::uint32_t i, std::uint32_t j) {
    if (color[i] != color[j]) return color[i] < color[j];
    if (cons[i].kind != cons[j].kind) return cons[i].kind < cons[j].kind;
    const std::uint32_t oi = cons[i].b - cons[i].a, oj = cons[j].b - cons[j].a;
    if (oi != oj) return oi < oj;
    if (cons[i].a != cons[j].a) return cons[i].a < cons[j].a;
    return i < j;
  });
  // a colour must never touch a particle twice
  {
    std::vector<std::uint32_t> seen(n, 0xffffffffu), by(n, 0);
    for (std::uint32_t o : order) {
      for (std::uint32_t p : {cons[o].a, cons[o].b}) {
        if (seen[p] == color[o])
          throw Error(idx(where, "colors", o) + ": colour " + std::to_string(color[o]) + " holds constraints " +
                      std::to_string(by[p]) + " and " + std::to_string(o) + " sharing particle " + std::to_string(p));
        seen[p] = color[o];
        by[p] = o;
      }
    }
  }

  auto impl = std::make_unique<Impl>();
  Impl& s = *impl;
  s.def = def;
  // particles
  auto f = [](double v) { return static_cast<float>(v); };
  s.x.resize(n), s.y.resize(n), s.z.resize(n), s.vx.resize(n), s.vy.resize(n), s.vz.resize(n);
  s.w.resize(n), s.mass.resize(n), s.pinned.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    s.x[i] = f(m.positions[i].x), s.y[i] = f(m.positions[i].y), s.z[i] = f(m.positions[i].z);
    if (!m.velocities.empty())
      s.vx[i] = f(m.velocities[i].x), s.vy[i] = f(m.velocities[i].y), s.vz[i] = f(m.velocities[i].z);
    s.mass[i] = m.masses[i];
    s.w[i] = f(1.0 / m.masses[i]);
  }
  s.n = n;
  for (auto* col : {&s.x, &s.y, &s.z, &s.w, &s.vx, &s.vy, &s.vz}) col->resize(n + detail::kSoftPad, 0.f);
  s.px = s.x, s.py = s.y, s.pz = s.z;
  // rest shape and tethers (filled before the first step)
  s.rx.assign(s.x.begin(), s.x.begin() + static_cast<std::ptrdiff_t>(n));
  s.ry.assign(s.y.begin(), s.y.begin() + static_cast<std::ptrdiff_t>(n));
  s.rz.assign(s.z.begin(), s.z.begin() + static_cast<std::ptrdiff_t>(n));
  s.tether.resize(n), s.tether_len.assign(n, detail::kNoTether);
  s.anchor_x.assign(n, 0.f), s.anchor_y.assign(n, 0.f), s.anchor_z.assign(n, 0.f);
  for (std::size_t i = 0; i < n; ++i) s.tether[i] = static_cast<std::uint32_t>(i);
  s.ax.assign(n, 0.f), s.ay.assign(n, 0.f), s.az.assign(n, 0.f);
  // constraints in solver order, runs per colour
  const std::size_t nc = cons.size();
  s.ca.resize(nc), s.cb.resize(nc), s.rest.resize(nc), s.kind.resize(nc), s.broken.assign(nc, 0);
  s.lambda.assign(nc, 0.f);
  std::vector<std::uint32_t> position_of(nc);
  for (std::size_t k = 0; k < nc; ++k) {
    const SoftConstraint& c = cons[order[k]];
    s.ca[k] = c.a, s.cb[k] = c.b, s.rest[k] = f(c.rest_length), s.kind[k] = static_cast<std::uint8_t>(c.kind);
    position_of[order[k]] = static_cast<std::uint32_t>(k);
  }
  s.rest0 = s.rest;
  s.rest.resize(nc + detail::kSoftPad, 0.f);
  s.lambda.resize(nc + detail::kSoftPad, 0.f);
  for (std::uint32_t k = 0; k < nc;) {
    std::uint32_t e = k;
    while (e < nc && color[order[e]] == color[order[k]]) ++e;
    make_runs(k, e, color[order[k]], s.ca, s.cb, s.kind, s.runs);
    k = e;
  }
  s.n_colors = n_colors;
  // rest lengths shared by a whole run are read once per run, not per constraint
  for (detail::Run& r : s.runs) {
    bool same = true;
    for (std::uint32_t c = r.c0 + 1; c < r.c0 + r.count && same; ++c) same = s.rest[c] == s.rest[r.c0];
    r.rest = same ? s.rest[r.c0] : -1.f;
  }
  s.run_of.resize(nc);
  for (std::size_t r = 0; r < s.runs.size(); ++r)
    for (std::uint32_t c = s.runs[r].c0; c < s.runs[r].c0 + s.runs[r].count; ++c)
      s.run_of[c] = static_cast<std::uint32_t>(r);
  // tetrahedra
  s.tets = std::move(tets);
  s.tet_rest = std::move(tet_rest);
  s.tet_lambda.assign(s.tets.size(), 0.f);
  s.rest_volume = rest_volume;
  // triangles and the constraint on each of their edges (for tearing)
  s.tris_all = m.triangles;
  s.tri_edges.resize(s.tris_all.size());
  {
    std::unordered_map<std::uint64_t, std::uint32_t> edge;
    edge.reserve(nc);
    auto key = [](std::uint32_t a, std::uint32_t b) {
      return a < b ? (std::uint64_t(a) << 32 | b) : (std::uint64_t(b) << 32 | a);
    };
    for (std::uint32_t k = 0; k < nc; ++k) edge.emplace(key(s.ca[k], s.cb[k]), k);
    for (std::size_t k = 0; k < s.tris_all.size(); ++k) {
      const SoftTriangle& t = s.tris_all[k];
      const std::uint32_t e3[3][2] = {{t.a, t.b}, {t.b, t.c}, {t.c, t.a}};
      for (int j = 0; j < 3; ++j) {
        auto it = edge.find(key(e3[j][0], e3[j][1]));
        s.tri_edges[k][j] = it == edge.end() ? kNoParticle : it->second;
      }
    }
  }
  s.tris = s.tris_all;
  s.init_tethers();
  // pins, scratch and the mass-spring integrator
  SoftBody body(std::move(impl));
  for (std::uint32_t p : m.pinned)
    if (!body.is_pinned(p)) body.pin(p);
  Impl& b = *body.impl_;
  b.pin_from.reserve(n), b.pin_to.reserve(n), b.pins.reserve(n);
  b.integ.set_method(def.method);
  return body;
}

// ---------------------------------------------------------------------------------------
// settings, stepping and the shared pieces of the solvers

SoftBodyDef& SoftBody::settings() { return impl_->def; }
const SoftBodyDef& SoftBody::settings() const { return impl_->def; }
long long SoftBody::steps() const { return impl_->steps; }
double SoftBody::time() const { return impl_->time; }
bool SoftBody::failed() const { return !impl_->failure.empty(); }
const SoftProfile& SoftBody::profile() const { return impl_->profile; }

void SoftBody::step(double t, double dt, std::span<const Collider> colliders) {
  // a failed body repeats its failure before looking at its inputs
  if (!impl_->failure.empty()) throw Error(impl_->failure);
  impl_->span_world.assign(colliders, "SoftBody::step colliders");
  step(t, dt, impl_->span_world);
}

void SoftBody::step(double t, double dt, const CollisionWorld& colliders) {
  Impl& s = *impl_;
  Stopwatch total;
  // a failed body repeats its failure
  if (!s.failure.empty()) throw Error(s.failure);
  require_finite(t, "SoftBody::step(t)");
  require_positive(dt, "SoftBody::step(dt)");
  s.def.validate("SoftBodyDef");
  // the substep in float: normal, with a finite square (1e-300 rounded to 0 and 1e300 to
  // inf, and the state turned NaN)
  if (const double h = dt / s.def.substeps; !detail::squarable<float>(h))
    detail::throw_not_squarable<float>(h, "SoftBody::step(dt): the substep dt / SoftBodyDef.substeps = " +
                                              format_value(dt) + " / " + std::to_string(s.def.substeps) + " s",
                                       "s", "it is used in float, divided by and squared");
  // A contact pushes a touching particle up to the thickness out of a collider within one
  // substep h. The XPBD solver takes its velocity from that displacement: it leaves at up
  // to thickness / h. The mass-spring solver keeps only the velocity out of the surface,
  // but a thick curved collider pushes neighbours out by different amounts and the
  // stretched springs pull them back at speeds of that order. The drag squares the speed relative to the wind in float and the
  // constraints the lengths the next substep moves it, so that speed must stay within
  // kMaxParticleSpeed (half of sqrt(FLT_MAX), the particles' own limit): thickness <=
  // kMaxParticleSpeed h. (Until 2026-12-07 the bound was sqrt(FLT_MAX) / 64 = 2.9e17 m at
  // every h, and an XPBD cloth on a sphere left it at 7.9e19 m/s at 1/600 s; 1e30 m made a
  // cloth on the ground NaN at the first step.) Refused before anything moves.
  if (const double h = dt / s.def.substeps, most = kMaxParticleSpeed * h; !(s.def.thickness <= most))
    throw Error("SoftBodyDef.thickness: must be at most kMaxParticleSpeed h = " + format_value(kMaxParticleSpeed) +
                " m/s * " + format_value(h) + " s = " + format_value(most) +
                " m at the substep h = dt / substeps (a contact pushes a particle this far out of a collider in one "
                "substep, which it leaves at thickness / h, and the float solver squares that speed), got " +
                format_value(s.def.thickness) + " m");
  if (s.x.empty()) {
    s.time = t + dt;
    ++s.steps;
    return;
  }
  // per-step inputs: colliders, wind and aerodynamics
  Stopwatch sw;
  s.colliders = colliders.flat_double();
  s.external_accelerations(t);
  // what predict forms in float: each substep adds a h^2 (gravity and the external
  // accelerations), and over the step's S substeps a free particle falls a h^2 S (S + 1) / 2
  // <= a dt^2. The constraints square the distances between particles in float, so that
  // travel must be squarable there (<= sqrt(FLT_MAX), 1.8e19 m): a rope at dt = 1e20 passed the
  // substep check, h^2 = 1e38, and its g h^2 turned the state non-finite; a cloth whose
  // aerodynamics accelerated it by 1e31 m/s^2 was flung 1e27 m in a step, and its squared
  // lengths made its pins NaN. Refused before any particle moves, naming the aerodynamics
  // when they alone go past the bound
  {
    const double bound = detail::squarable_hi<float>(), g = glm::length(s.def.forces.gravity);
    double a2 = 0;
    std::size_t worst = 0;
    if (s.has_aext)
      for (std::size_t i = 0; i < s.n; ++i) {  // (x is padded: n + kSoftPad columns)
        const double ax = s.ax[i], ay = s.ay[i], az = s.az[i], q = ax * ax + ay * ay + az * az;
        if (q > a2) a2 = q, worst = i;
      }
    const double aero = std::sqrt(a2), a = g + aero;
    if (!(aero * dt * dt <= bound))
      throw Error("SoftBodyDef.aero: the aerodynamic force on particle " + std::to_string(worst) + " (air density " +
                  format_value(s.def.aero.air_density) + " kg/m^3, drag " + format_value(s.def.aero.drag) +
                  ", lift " + format_value(s.def.aero.lift) + ") accelerates it by " + format_value(aero) +
                  " m/s^2, which moves it up to a dt^2 = " + format_value(aero * dt * dt) + " m in one step of " +
                  format_value(dt) + " s, beyond what the float solve squares (" + format_value(bound) +
                  " m): lower the drag and lift coefficients");
    if (!(a * dt * dt <= bound))
      throw Error("SoftBody::step(dt): dt = " + format_value(dt) + " s with accelerations up to " + format_value(a) +
                  " m/s^2 (gravity and aerodynamics) moves a particle up to a dt^2 = " + format_value(a * dt * dt) +
                  " m in one step, beyond what the float solve squares (" + format_value(bound) +
                  " m); use a smaller dt");
  }
  s.profile.forces = sw.seconds();
  s.profile.collide = 0;
  // the solver
  sw.reset();
  if (s.def.solver == SoftSolver::Xpbd) {
    s.ms_valid = false;
    s.step_xpbd(t, dt);
  } else {
    s.step_mass_spring(t, dt);
  }
  // (the collisions' time is measured within the solver's, so the difference is >= 0)
  s.profile.solve = std::max(0.0, sw.seconds() - s.profile.collide);
  // pins end exactly at their targets
  for (std::size_t k = 0; k < s.pins.size(); ++k) s.pin_from[k] = s.pin_to[k];
  // tearing, then the finite check
  if (s.def.tear_strain > 0) s.tear();
  s.time = t + dt;
  ++s.steps;
  s.check_finite(t + dt, dt / s.def.substeps);
  s.profile.total = total.seconds();
}

// Per-triangle aerodynamic drag and lift (Keckeisen, Kimmerle, Thomaszewski & Wacker 2004,
// "Modelling effects of wind fields in cloth animations", eqs. 2-3; the two-sided model of
// Bullet's btSoftBody aero): with the air-relative velocity u of the triangle's centroid,
// unit normal n and area A, drag F_d = -1/2 rho C_d A |u| (u.n) n and lift
// F_l = -1/2 rho C_l A (u.n) (|u|^2 n - (u.n) u)/|u|, a third to each corner.
void SoftBody::Impl::external_accelerations(double t) {
  has_aext = false;
  const bool aero = (def.aero.drag > 0 || def.aero.lift > 0) && def.aero.air_density > 0 && !tris.empty();
  if (!aero) return;
  std::fill(ax.begin(), ax.end(), 0.f);
  std::fill(ay.begin(), ay.end(), 0.f);
  std::fill(az.begin(), az.end(), 0.f);
  has_aext = true;
  const Vec3 wind = def.forces.wind.at(t);
  const double k = 0.5 * def.aero.air_density;
  for (const SoftTriangle& tr : tris) {
    // centroid velocity relative to the air, area-weighted normal
    const Vec3 pa(x[tr.a], y[tr.a], z[tr.a]), pb(x[tr.b], y[tr.b], z[tr.b]), pc(x[tr.c], y[tr.c], z[tr.c]);
    const Vec3 u = (Vec3(vx[tr.a], vy[tr.a], vz[tr.a]) + Vec3(vx[tr.b], vy[tr.b], vz[tr.b]) +
                    Vec3(vx[tr.c], vy[tr.c], vz[tr.c])) / 3.0 - wind;
    const Vec3 cr = glm::cross(pb - pa, pc - pa);
    const double len2 = glm::dot(cr, cr), u2 = glm::dot(u, u);
    if (!(len2 > 0) || !(u2 > 0)) continue;
    const double cl = std::sqrt(len2), area = 0.5 * cl, speed = std::sqrt(u2);
    const Vec3 n = cr * (1.0 / cl);
    const double un = glm::dot(u, n);
    // drag along the normal and lift across the flow, a third to each corner
    Vec3 F = (-k * def.aero.drag * area * speed * un) * n;
    F += (-k * def.aero.lift * area * un / speed) * (u2 * n - un * u);
    const Vec3 third = F * (1.0 / 3.0);
    for (std::uint32_t p : {tr.a, tr.b, tr.c}) {
      // a pinned corner takes none (w = 0; an infinite force would make it 0 * inf = NaN;
      // adding its +0 or -0 changed no bit of its +0 sum)
      if (w[p] == 0) continue;
      // an acceleration beyond a float is the coefficients' doing (C_d = 1e300): named here,
      // before anything moves, rather than as a step too long or a non-finite particle; the
      // triangles' shares too, whose float sum can overflow where none of them does (a grid's
      // inner particle takes six)
      const Vec3 acc = third * double(w[p]);
      if (!(std::abs(acc.x) + std::abs(acc.y) + std::abs(acc.z) <= std::numeric_limits<float>::max()))
        aero_overflow(p, acc, u);
      const float sx = ax[p] + static_cast<float>(acc.x), sy = ay[p] + static_cast<float>(acc.y),
                  sz = az[p] + static_cast<float>(acc.z);
      if (!(std::isfinite(sx) && std::isfinite(sy) && std::isfinite(sz))) aero_overflow(p, Vec3(sx, sy, sz), u);
      ax[p] = sx, ay[p] = sy, az[p] = sz;
    }
  }
}

void SoftBody::Impl::aero_overflow(std::uint32_t p, const Vec3& acc, const Vec3& u) const {
  throw Error("SoftBodyDef.aero: the aerodynamic force on particle " + std::to_string(p) + " (air density " +
              format_value(def.aero.air_density) + " kg/m^3, drag " + format_value(def.aero.drag) + ", lift " +
              format_value(def.aero.lift) + ", air-relative speed " + format_value(glm::length(u)) +
              " m/s) accelerates it by " + format_vec3(acc) + " m/s^2, beyond a float (3.4e38): lower the drag and lift "
              "coefficients");
}

// Tearing: a constraint whose strain (l - l0)/l0 exceeds tear_strain breaks for good (its
// rest length becomes -1, which masks it in the kernels); triangles on a broken edge go.
void SoftBody::Impl::tear() {
  const float limit = static_cast<float>(def.tear_strain);
  bool any = false;
  for (std::size_t c = 0; c < ca.size(); ++c) {
    if (broken[c]) continue;
    const float dx = x[cb[c]] - x[ca[c]], dy = y[cb[c]] - y[ca[c]], dz = z[cb[c]] - z[ca[c]];
    const float l = std::sqrt(dx * dx + dy * dy + dz * dz);
    if ((l - rest0[c]) > limit * rest0[c]) {
      broken[c] = 1;
      rest[c] = -1.f;
      runs[run_of[c]].rest = -1.f;  // its run now reads the per-constraint lengths
      lambda[c] = 0.f;
      ++n_broken;
      any = true;
    }
  }
  if (any) rebuild_triangles();
}

void SoftBody::Impl::rebuild_triangles() {
  // keep the triangles whose edges are all intact (no allocation: capacity is kept)
  tris.clear();
  for (std::size_t k = 0; k < tris_all.size(); ++k) {
    bool ok = true;
    for (std::uint32_t e : tri_edges[k]) ok = ok && (e == kNoParticle || !broken[e]);
    if (ok) tris.push_back(tris_all[k]);
  }
}

void SoftBody::Impl::check_finite(double t, double h) {
  // one pass with a sum of x - x (0 when finite, nan otherwise), then find the culprit
  float acc = 0.f;
  for (std::size_t i = 0; i < n; ++i)
    acc += (x[i] - x[i]) + (y[i] - y[i]) + (z[i] - z[i]) + (vx[i] - vx[i]) + (vy[i] - vy[i]) + (vz[i] - vz[i]);
  if (acc == 0.f) return;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 p(x[i], y[i], z[i]), v(vx[i], vy[i], vz[i]);
    if (is_finite(p) && is_finite(v)) continue;
    failure = "soft body particle " + std::to_string(i) + " became non-finite at t = " + format_value(t) + " s (step " +
              std::to_string(steps) + "): position " + format_vec3(p) + ", velocity " + format_vec3(v);
    // an explicit integrator past its stability bound: say which settings put it there
    if (const std::string why = mass_spring_instability(h); !why.empty()) failure += "; unstable: " + why;
    throw Error(failure);
  }
}


// ---------------------------------------------------------------------------------------
// particles

std::size_t SoftBody::size() const { return impl_->n; }

namespace {
void check_particle(std::size_t i, std::size_t n, std::string_view where) {
  if (i >= n)
    throw Error(std::string(where) + ": particle " + std::to_string(i) + " does not exist (the body has " +
                std::to_string(n) + " particles)");
}
}  // namespace

Vec3 SoftBody::position(std::size_t i) const {
  check_particle(i, size(), "SoftBody::position");
  return {impl_->x[i], impl_->y[i], impl_->z[i]};
}
Vec3 SoftBody::velocity(std::size_t i) const {
  check_particle(i, size(), "SoftBody::velocity");
  return {impl_->vx[i], impl_->vy[i], impl_->vz[i]};
}
double SoftBody::mass(std::size_t i) const {
  check_particle(i, size(), "SoftBody::mass");
  return impl_->w[i] == 0.f ? std::numeric_limits<double>::infinity() : impl_->mass[i];
}
double SoftBody::inverse_mass(std::size_t i) const {
  check_particle(i, size(), "SoftBody::inverse_mass");
  return impl_->w[i];
}
double SoftBody::total_mass() const { return std::accumulate(impl_->mass.begin(), impl_->mass.end(), 0.0); }

void SoftBody::set_position(std::size_t i, const Vec3& p) {
  check_particle(i, size(), "SoftBody::set_position");
  require_finite(p, "SoftBody::set_position(p)");
  Impl& s = *impl_;
  s.x[i] = s.px[i] = static_cast<float>(p.x);
  s.y[i] = s.py[i] = static_cast<float>(p.y);
  s.z[i] = s.pz[i] = static_cast<float>(p.z);
  s.ms_valid = false;
}
void SoftBody::set_velocity(std::size_t i, const Vec3& v) {
  check_particle(i, size(), "SoftBody::set_velocity");
  require_finite(v, "SoftBody::set_velocity(v)");
  Impl& s = *impl_;
  s.vx[i] = static_cast<float>(v.x), s.vy[i] = static_cast<float>(v.y), s.vz[i] = static_cast<float>(v.z);
  s.ms_valid = false;
}
void SoftBody::add_velocity(const Vec3& dv) {
  require_finite(dv, "SoftBody::add_velocity(dv)");
  Impl& s = *impl_;
  for (std::size_t i = 0; i < size(); ++i) {
    if (s.w[i] == 0.f) continue;
    s.vx[i] += static_cast<float>(dv.x), s.vy[i] += static_cast<float>(dv.y), s.vz[i] += static_cast<float>(dv.z);
  }
  s.ms_valid = false;
}
std::span<const float> SoftBody::xs() const { return impl_->x; }
std::span<const float> SoftBody::ys() const { return impl_->y; }
std::span<const float> SoftBody::zs() const { return impl_->z; }
void SoftBody::copy_positions(std::span<Vec3f> out) const {
  if (out.size() != size())
    throw Error("SoftBody::copy_positions(out): size must be " + std::to_string(size()) + ", got " +
                std::to_string(out.size()));
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = Vec3f(impl_->x[i], impl_->y[i], impl_->z[i]);
}

// ---------------------------------------------------------------------------------------
// pins and grabbing

void SoftBody::pin(std::size_t i) {
  check_particle(i, size(), "SoftBody::pin");
  pin(i, position(i));
}

void SoftBody::pin(std::size_t i, const Vec3& target) {
  check_particle(i, size(), "SoftBody::pin");
  require_finite(target, "SoftBody::pin(target)");
  Impl& s = *impl_;
  if (s.pinned[i]) {
    set_pin_target(i, target);
    return;
  }
  // kinematic: inverse mass 0, slides from where it is to the target over the next step
  s.pinned[i] = 1;
  s.w[i] = 0.f;
  s.pins.push_back(static_cast<std::uint32_t>(i));
  s.pin_from.push_back(position(i));
  s.pin_to.push_back(target);
  s.ms_valid = false;
  s.tethers_dirty = true;
}

void SoftBody::unpin(std::size_t i) {
  check_particle(i, size(), "SoftBody::unpin");
  Impl& s = *impl_;
  if (!s.pinned[i]) return;
  // restore the mass and forget the pin (order of the others kept)
  const auto k = static_cast<std::size_t>(std::find(s.pins.begin(), s.pins.end(), i) - s.pins.begin());
  s.pins.erase(s.pins.begin() + static_cast<std::ptrdiff_t>(k));
  s.pin_from.erase(s.pin_from.begin() + static_cast<std::ptrdiff_t>(k));
  s.pin_to.erase(s.pin_to.begin() + static_cast<std::ptrdiff_t>(k));
  s.pinned[i] = 0;
  s.w[i] = static_cast<float>(1.0 / s.mass[i]);
  if (s.grab == i) s.grab = kNoParticle;
  s.ms_valid = false;
  s.tethers_dirty = true;
}

bool SoftBody::is_pinned(std::size_t i) const {
  check_particle(i, size(), "SoftBody::is_pinned");
  return impl_->pinned[i] != 0;
}

void SoftBody::set_pin_target(std::size_t i, const Vec3& target) {
  check_particle(i, size(), "SoftBody::set_pin_target");
  require_finite(target, "SoftBody::set_pin_target(target)");
  Impl& s = *impl_;
  if (!s.pinned[i]) throw Error("SoftBody::set_pin_target: particle " + std::to_string(i) + " is not pinned");
  const auto k = static_cast<std::size_t>(std::find(s.pins.begin(), s.pins.end(), i) - s.pins.begin());
  s.pin_to[k] = target;
}

std::span<const std::uint32_t> SoftBody::pins() const { return impl_->pins; }

void SoftBody::grab(std::size_t i, const Vec3& target) {
  check_particle(i, size(), "SoftBody::grab");
  require_finite(target, "SoftBody::grab(target)");
  release();
  Impl& s = *impl_;
  s.grab_pinned = !s.pinned[i];
  if (s.grab_pinned) pin(i, target);
  else set_pin_target(i, target);
  s.grab = static_cast<std::uint32_t>(i);
}

void SoftBody::move_grab(const Vec3& target) {
  // named by this call (set_pin_target's check named set_pin_target), and refused with
  // nothing grabbed too: a bad target is the caller's bug either way
  require_finite(target, "SoftBody::move_grab(target)");
  if (impl_->grab == kNoParticle) return;
  set_pin_target(impl_->grab, target);
}

void SoftBody::release() {
  Impl& s = *impl_;
  if (s.grab == kNoParticle) return;
  const std::uint32_t g = s.grab;
  s.grab = kNoParticle;
  if (s.grab_pinned) unpin(g);
}

std::uint32_t SoftBody::grabbed() const { return impl_->grab; }

std::uint32_t SoftBody::nearest_particle(const Vec3& point) const {
  require_finite(point, "SoftBody::nearest_particle(point)");
  std::uint32_t best = kNoParticle;
  double best_d2 = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < size(); ++i) {
    const Vec3 d = Vec3(impl_->x[i], impl_->y[i], impl_->z[i]) - point;
    const double d2 = glm::dot(d, d);
    if (d2 < best_d2) best_d2 = d2, best = static_cast<std::uint32_t>(i);
  }
  return best;
}

std::uint32_t SoftBody::nearest_particle(const Vec3& origin, const Vec3& direction, double radius) const {
  require_finite(origin, "SoftBody::nearest_particle(origin)");
  require_finite(direction, "SoftBody::nearest_particle(direction)");
  require_positive(radius, "SoftBody::nearest_particle(radius)");
  const double len = glm::length(direction);
  if (!(len > 0)) throw Error("SoftBody::nearest_particle(direction): must be non-zero, got (0, 0, 0)");
  const Vec3 d = direction / len;
  std::uint32_t best = kNoParticle;
  double best_s = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < size(); ++i) {
    // distance from the ray, then the one nearest the origin
    const Vec3 r = Vec3(impl_->x[i], impl_->y[i], impl_->z[i]) - origin;
    const double s = glm::dot(r, d);
    if (s < 0) continue;
    const Vec3 perp = r - s * d;
    if (glm::dot(perp, perp) > radius * radius) continue;
    if (s < best_s) best_s = s, best = static_cast<std::uint32_t>(i);
  }
  return best;
}

// ---------------------------------------------------------------------------------------
// structure and measurements

std::size_t SoftBody::constraint_count() const { return impl_->ca.size(); }

SoftConstraint SoftBody::constraint(std::size_t c) const {
  if (c >= constraint_count())
    throw Error("SoftBody::constraint: constraint " + std::to_string(c) + " does not exist (the body has " +
                std::to_string(constraint_count()) + ")");
  const Impl& s = *impl_;
  return {.a = s.ca[c], .b = s.cb[c], .rest_length = s.rest0[c],
          .kind = static_cast<SoftConstraintKind>(s.kind[c]), .broken = s.broken[c] != 0};
}

std::size_t SoftBody::broken_constraints() const { return impl_->n_broken; }
std::span<const SoftTriangle> SoftBody::triangles() const { return impl_->tris; }
std::span<const SoftTet> SoftBody::tets() const { return impl_->tets; }
std::size_t SoftBody::color_count() const {
  return impl_->n_colors;
}

double SoftBody::kinetic_energy() const {
  const Impl& s = *impl_;
  double e = 0;
  for (std::size_t i = 0; i < size(); ++i) {
    if (s.pinned[i]) continue;
    const double v2 = double(s.vx[i]) * s.vx[i] + double(s.vy[i]) * s.vy[i] + double(s.vz[i]) * s.vz[i];
    e += 0.5 * s.mass[i] * v2;
  }
  return e;
}


double SoftBody::potential_energy() const {
  const Impl& s = *impl_;
  const SoftBodyDef& d = s.def;
  double e = 0;
  // gravity over the free particles
  for (std::size_t i = 0; i < size(); ++i) {
    if (s.pinned[i]) continue;
    e -= s.mass[i] * glm::dot(d.forces.gravity, Vec3(s.x[i], s.y[i], s.z[i]));
  }
  // elastic energy of the distance constraints: k C^2 / 2 with k = 1/alpha for XPBD
  const bool xpbd = d.solver == SoftSolver::Xpbd;
  for (std::size_t c = 0; c < s.ca.size(); ++c) {
    if (s.broken[c]) continue;
    const auto kd = static_cast<SoftConstraintKind>(s.kind[c]);
    double k;
    if (xpbd) {
      const double alpha = detail::kind_compliance(d, kd);
      if (!(alpha > 0)) continue;
      k = 1.0 / alpha;
    } else {
      k = detail::kind_stiffness(d, kd);
    }
    const Vec3 pa(s.x[s.ca[c]], s.y[s.ca[c]], s.z[s.ca[c]]), pb(s.x[s.cb[c]], s.y[s.cb[c]], s.z[s.cb[c]]);
    const double C = glm::length(pb - pa) - s.rest0[c];
    e += 0.5 * k * C * C;
  }
  // volume constraints
  const double kv = xpbd ? (d.volume_compliance > 0 ? 1.0 / d.volume_compliance : 0.0) : d.volume_stiffness;
  if (kv > 0) {
    for (std::size_t k = 0; k < s.tets.size(); ++k) {
      const SoftTet& t = s.tets[k];
      auto P = [&](std::uint32_t i) { return Vec3(s.x[i], s.y[i], s.z[i]); };
      const double C = tet_volume(P(t.a), P(t.b), P(t.c), P(t.d)) - s.tet_rest[k];
      e += 0.5 * kv * C * C;
    }
  }
  return e;
}

StrainStats SoftBody::strain_stats() const {
  const Impl& s = *impl_;
  StrainStats st;
  std::size_t count = 0;
  for (std::size_t c = 0; c < s.ca.size(); ++c) {
    if (s.broken[c] || s.kind[c] != static_cast<std::uint8_t>(SoftConstraintKind::Stretch)) continue;
    const Vec3 pa(s.x[s.ca[c]], s.y[s.ca[c]], s.z[s.ca[c]]), pb(s.x[s.cb[c]], s.y[s.cb[c]], s.z[s.cb[c]]);
    const double strain = std::abs(glm::length(pb - pa) - s.rest0[c]) / s.rest0[c];
    st.mean += strain;
    st.max = std::max(st.max, strain);
    ++count;
  }
  if (count) st.mean /= static_cast<double>(count);
  return st;
}

double SoftBody::volume() const {
  const Impl& s = *impl_;
  double v = 0;
  auto P = [&](std::uint32_t i) { return Vec3(s.x[i], s.y[i], s.z[i]); };
  for (const SoftTet& t : s.tets) v += tet_volume(P(t.a), P(t.b), P(t.c), P(t.d));
  return v;
}

double SoftBody::rest_volume() const { return impl_->rest_volume; }

Vec3 SoftBody::center_of_mass() const {
  const Impl& s = *impl_;
  Vec3 sum(0, 0, 0);
  double m = 0;
  for (int pass = 0; pass < 2 && m == 0; ++pass) {
    for (std::size_t i = 0; i < size(); ++i) {
      if (pass == 0 && s.pinned[i]) continue;
      sum += s.mass[i] * Vec3(s.x[i], s.y[i], s.z[i]);
      m += s.mass[i];
    }
  }
  return m > 0 ? sum / m : sum;
}

std::uint64_t SoftBody::hash(std::uint64_t seed) const {
  const Impl& s = *impl_;
  std::uint64_t h = seed;
  for (const auto* col : {&s.x, &s.y, &s.z, &s.vx, &s.vy, &s.vz})
    h = hash_span(std::span<const float>(col->data(), s.n), h);
  return hash_span(std::span<const std::uint8_t>(s.broken), h);
}

void SoftBody::draw(DebugDraw& dd, const DrawFlags& flags, const SoftDrawOptions& o) const {
  const Impl& s = *impl_;
  auto P = [&](std::uint32_t i) { return Vec3(s.x[i], s.y[i], s.z[i]); };
  // triangles, shaded by how much they face a fixed light
  if (o.triangles) {
    const Vec3 light = glm::normalize(Vec3(0.4, 1.0, 0.6));
    for (const SoftTriangle& t : s.tris) {
      const Vec3 a = P(t.a), b = P(t.b), c = P(t.c);
      const Vec3 cr = glm::cross(b - a, c - a);
      const double len = glm::length(cr);
      const float shade = len > 0 ? static_cast<float>(0.45 + 0.55 * std::abs(glm::dot(cr / len, light))) : 0.45f;
      dd.triangle(a, b, c, Color{o.color.r * shade, o.color.g * shade, o.color.b * shade, o.color.a});
    }
  }
  // edges, coloured by strain
  if (o.edges && flags.constraints) {
    const double scale = o.strain_scale > 0 ? o.strain_scale : 0.1;
    for (std::size_t c = 0; c < s.ca.size(); ++c) {
      if (s.broken[c]) continue;
      if (!o.all_edges && s.kind[c] != static_cast<std::uint8_t>(SoftConstraintKind::Stretch)) continue;
      const Vec3 a = P(s.ca[c]), b = P(s.cb[c]);
      Color col = o.color;
      if (o.strain_colors) {
        const float u = static_cast<float>(std::min(1.0, std::abs(glm::length(b - a) / s.rest0[c] - 1.0) / scale));
        col = Color{o.color.r + (colors::red.r - o.color.r) * u, o.color.g + (colors::red.g - o.color.g) * u,
                    o.color.b + (colors::red.b - o.color.b) * u, o.color.a};
      }
      dd.line(a, b, col);
    }
  }
  // particles, pins and the grabbed particle
  if (o.particles && flags.particles)
    for (std::size_t i = 0; i < size(); ++i) dd.point(P(static_cast<std::uint32_t>(i)), 3.f, o.color);
  if (o.pins && flags.particles) {
    for (std::uint32_t p : s.pins) dd.point(P(p), 7.f, p == s.grab ? colors::yellow : colors::orange);
  }
}

}  // namespace pba
