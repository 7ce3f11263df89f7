// Soft body builders: a spring, a rope, a cloth grid and a jelly box, each a SoftMesh
// handed to SoftBody::from_mesh. The rope and cloth builders colour their constraints
// themselves so that every colour splits into long contiguous or interleaved runs.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <set>
#include <string>
#include <utility>

#include "soft_impl.h"

namespace pba {

namespace {

void positive(double v, std::string_view where) {
  if (!(std::isfinite(v) && v > 0)) require_positive(v, where);
}

// Whether cell i of n along an axis is split as the mirror image of the Kuhn cell:
// cells alternate (so the lattice is locally isotropic: the four diagonal directions
// and both diagonals of every face kind occur equally in each 2 x 2 x 2 block) and cell
// n-1-i is the mirror image of cell i about the mid-plane (exactly so for even n; for
// odd n the middle cell has no partner). With d = 2i + 1 - n (the cell centre's offset
// from the mid-plane in half cells): flipped past the mid-plane, toggled every cell.
int mirrored(int i, int n) {
  const int d = 2 * i + 1 - n;
  return (d > 0 ? 1 : 0) ^ ((std::abs(d) / 2) % 2);
}

// The float state: positions and velocities are stored as float, masses as float
// inverses. Checked on the mesh a builder made, so the message names the particle and the
// fields of the definition that placed it.
void require_float_state(const SoftMesh& m, std::string_view where, std::string_view fields) {
  for (std::size_t i = 0; i < m.positions.size(); ++i) {
    if (!fits_float(m.positions[i]))
      throw Error(std::string(where) + ": particle " + std::to_string(i) + " at " + format_vec3(m.positions[i]) +
                  " does not fit a float (|coordinate| <= " + format_value(std::numeric_limits<float>::max()) +
                  "); see " + std::string(fields));
    if (!m.velocities.empty() && !fits_float(m.velocities[i]))
      require_float(m.velocities[i], field_path(where, "velocity"));
  }
  // the masses a builder gives are equal (split evenly): the first one speaks for all
  if (!m.masses.empty() && !std::isnormal(static_cast<float>(1.0 / m.masses[0])))
    require_float_inverse(m.masses[0], std::string(where) + ".mass split among " + std::to_string(m.masses.size()) +
                                           " particles (kg each)");
}

// A cloth grid's memory, counted before anything is allocated.
void require_cloth_memory(const ClothDef& c) {
  const double nx = c.nx, ny = c.ny;
  const double particles = nx * ny;
  const double constraints = (ny - 1) * nx + ny * (nx - 1) + (c.shear ? 2 * (nx - 1) * (ny - 1) : 0) +
                             (c.bending ? (ny - 2) * nx + ny * (nx - 2) : 0);
  const double triangles = 2 * (nx - 1) * (ny - 1);
  const double bytes = particles * kSoftParticleBytes + constraints * kSoftConstraintBytes +
                       triangles * kSoftTriangleBytes;
  if (bytes <= static_cast<double>(kSoftBodyMemoryBudget)) return;
  throw Error("ClothDef.nx: a " + std::to_string(c.nx) + " x " + std::to_string(c.ny) + " cloth (" +
              format_value(particles) + " particles, " + format_value(constraints) + " constraints, " +
              format_value(triangles) + " triangles) would take " + format_bytes(bytes) +
              ", over a soft body's memory budget of " + format_bytes(static_cast<double>(kSoftBodyMemoryBudget)) +
              " (kSoftBodyMemoryBudget); use fewer particles per side");
}

}  // namespace

SoftBody SoftBody::spring(const SpringDef& sp, const SoftBodyDef& def) {
  // the ends, the mass and the spring constants
  require_finite(sp.a, "SpringDef.a");
  require_finite(sp.b, "SpringDef.b");
  require_float(sp.velocity_b, "SpringDef.velocity_b");
  positive(sp.mass, "SpringDef.mass");
  positive(sp.stiffness, "SpringDef.stiffness");
  // XPBD uses the compliance 1 / k: a denormal k (1e-310) made it inf, refused as
  // SoftBodyDef.stretch_compliance, a field the caller never set
  if (!std::isfinite(1 / sp.stiffness))
    throw Error("SpringDef.stiffness: must be at least " + format_value(1 / std::numeric_limits<double>::max()) +
                " N/m (XPBD uses its compliance 1 / k, which must be finite), got " + format_value(sp.stiffness));
  if (!(std::isfinite(sp.damping) && sp.damping >= 0)) require_non_negative(sp.damping, "SpringDef.damping");
  if (!std::isfinite(sp.rest_length)) require_finite(sp.rest_length, "SpringDef.rest_length");
  const double dist = glm::length(sp.b - sp.a);
  // coincident ends give the spring no direction (whatever its rest length), so no force
  if (!(dist > 0))
    throw Error("SpringDef.b: must differ from a (a spring between coincident ends has no direction), both at " +
                format_vec3(sp.a));
  if (sp.rest_length >= 0 && !(sp.rest_length > 0))
    throw Error("SpringDef.rest_length: must be > 0 (or negative for |b - a|), got " + format_value(sp.rest_length));
  // the spring's k and c replace the body's stretch settings (XPBD: alpha = 1/k)
  SoftBodyDef d = def;
  d.stretch_stiffness = sp.stiffness;
  d.stretch_compliance = 1.0 / sp.stiffness;
  d.spring_damping = sp.damping;
  SoftMesh m;
  m.positions = {sp.a, sp.b};
  m.velocities = {Vec3(0, 0, 0), sp.velocity_b};
  m.masses = {sp.mass, sp.mass};
  m.constraints = {{.a = 0, .b = 1, .rest_length = sp.rest_length < 0 ? dist : sp.rest_length}};
  if (sp.fixed_a) m.pinned = {0};
  require_float_state(m, "SpringDef", "a and b");
  return from_mesh(m, d, "SpringDef");
}

SoftBody SoftBody::rope(const RopeDef& r, const SoftBodyDef& def) {
  // shape
  require_finite(r.from, "RopeDef.from");
  require_finite(r.to, "RopeDef.to");
  require_count(r.segments, 1, 100000, "RopeDef.segments");
  positive(r.mass, "RopeDef.mass");
  if (!(glm::length(r.to - r.from) > 0))
    throw Error("RopeDef.to: must differ from RopeDef.from, both are " + format_vec3(r.from));
  const int n = r.segments + 1;
  SoftMesh m;
  m.positions.resize(n);
  m.masses.assign(n, r.mass / n);
  for (int i = 0; i < n; ++i) m.positions[i] = r.from + (r.to - r.from) * (double(i) / r.segments);
  // stretch (i, i+1) in two colours by parity; bend (i, i+2) in two by i mod 4
  for (int i = 0; i + 1 < n; ++i) {
    m.constraints.push_back({.a = std::uint32_t(i), .b = std::uint32_t(i + 1)});
    m.colors.push_back(i % 2);
  }
  if (r.bending) {
    for (int i = 0; i + 2 < n; ++i) {
      m.constraints.push_back({.a = std::uint32_t(i), .b = std::uint32_t(i + 2), .kind = SoftConstraintKind::Bend});
      m.colors.push_back(2 + (i % 4 < 2 ? 0 : 1));
    }
  }
  if (r.pin_start) m.pinned.push_back(0);
  if (r.pin_end) m.pinned.push_back(std::uint32_t(n - 1));
  require_float_state(m, "RopeDef", "from and to");
  return from_mesh(m, def, "RopeDef");
}

SoftBody SoftBody::cloth_grid(const ClothDef& c, const SoftBodyDef& def) {
  // shape
  require_finite(c.origin, "ClothDef.origin");
  require_finite(c.edge_u, "ClothDef.edge_u");
  require_finite(c.edge_v, "ClothDef.edge_v");
  if (c.nx < 2 || c.nx > 4096)
    throw Error("ClothDef.nx: cloth grids must be at least 2x2 (and at most 4096 per side), got nx = " +
                std::to_string(c.nx));
  if (c.ny < 2 || c.ny > 4096)
    throw Error("ClothDef.ny: cloth grids must be at least 2x2 (and at most 4096 per side), got ny = " +
                std::to_string(c.ny));
  positive(c.mass, "ClothDef.mass");
  if (!(glm::length(c.edge_u) > 0)) throw Error("ClothDef.edge_u: must be non-zero, got (0, 0, 0)");
  if (!(glm::length(c.edge_v) > 0)) throw Error("ClothDef.edge_v: must be non-zero, got (0, 0, 0)");
  if (!(glm::length(glm::cross(c.edge_u, c.edge_v)) > 1e-12 * glm::length(c.edge_u) * glm::length(c.edge_v)))
    throw Error("ClothDef.edge_v: must not be parallel to edge_u " + format_vec3(c.edge_u) + ", got " +
                format_vec3(c.edge_v));
  require_cloth_memory(c);
  const int nx = c.nx, ny = c.ny;
  const std::size_t n = std::size_t(nx) * ny;
  SoftMesh m;
  m.positions.resize(n);
  m.masses.assign(n, c.mass / double(n));
  auto id = [nx](int i, int j) { return std::uint32_t(j * nx + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      m.positions[id(i, j)] = c.origin + c.edge_u * (double(i) / (nx - 1)) + c.edge_v * (double(j) / (ny - 1));
  // 12 colours, each one parity class of one family, so that each is a set of long
  // contiguous (rows) or interleaved (along a row) runs
  auto add = [&](std::uint32_t a, std::uint32_t b, SoftConstraintKind k, std::uint32_t color) {
    m.constraints.push_back({.a = a, .b = b, .kind = k});
    m.colors.push_back(color);
  };
  using K = SoftConstraintKind;
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i < nx; ++i) add(id(i, j), id(i, j + 1), K::Stretch, 0 + j % 2);  // vertical
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) add(id(i, j), id(i + 1, j), K::Stretch, 2 + i % 2);  // horizontal
  if (c.shear) {
    for (int j = 0; j + 1 < ny; ++j)
      for (int i = 0; i + 1 < nx; ++i) add(id(i, j), id(i + 1, j + 1), K::Shear, 4 + j % 2);
    for (int j = 0; j + 1 < ny; ++j)
      for (int i = 0; i + 1 < nx; ++i) add(id(i + 1, j), id(i, j + 1), K::Shear, 6 + j % 2);
  }
  if (c.bending) {
    for (int j = 0; j + 2 < ny; ++j)
      for (int i = 0; i < nx; ++i) add(id(i, j), id(i, j + 2), K::Bend, 8 + (j % 4 < 2 ? 0 : 1));
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i + 2 < nx; ++i) add(id(i, j), id(i + 2, j), K::Bend, 10 + (i % 4 < 2 ? 0 : 1));
  }
  // two triangles per quad, counter-clockwise seen from edge_u x edge_v
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  // pins
  switch (c.pins) {
    case ClothPins::None: break;
    case ClothPins::FirstRow:
      for (int i = 0; i < nx; ++i) m.pinned.push_back(id(i, 0));
      break;
    case ClothPins::FirstRowCorners: m.pinned = {id(0, 0), id(nx - 1, 0)}; break;
    case ClothPins::FirstColumn:
      for (int j = 0; j < ny; ++j) m.pinned.push_back(id(0, j));
      break;
    default: throw Error("ClothDef.pins: unknown value " + std::to_string(static_cast<int>(c.pins)));
  }
  require_float_state(m, "ClothDef", "origin, edge_u and edge_v");
  return from_mesh(m, def, "ClothDef");
}

// The material's XPBD settings (derivation at the declaration in pba/soft.h): the edge
// stiffness from the shear modulus, the volume compliance from the rest of the bulk
// modulus, Rayleigh damping, and enough substeps to resolve an edge's vibration.
SoftBodyDef jelly_settings(const JellyDef& jd, const JellyMaterial& mat, double dt) {
  // the inputs it reads
  positive(jd.size.x, "JellyDef.size.x");
  positive(jd.size.y, "JellyDef.size.y");
  positive(jd.size.z, "JellyDef.size.z");
  require_count(jd.nx, 1, 64, "JellyDef.nx");
  require_count(jd.ny, 1, 64, "JellyDef.ny");
  require_count(jd.nz, 1, 64, "JellyDef.nz");
  positive(jd.mass, "JellyDef.mass");
  positive(mat.young, "JellyMaterial.young");
  if (!(mat.poisson >= 0.27 && mat.poisson <= 0.49))
    throw Error("JellyMaterial.poisson: must be in [0.27, 0.49] (the edges alone give 5/19; 0.5 locks), got " +
                format_value(mat.poisson));
  if (!(std::isfinite(mat.damping_time) && mat.damping_time >= 0))
    require_non_negative(mat.damping_time, "JellyMaterial.damping_time");
  positive(dt, "jelly_settings dt");
  // moduli and the cell edge a = cbrt(cell volume)
  const double g = mat.young / (2 * (1 + mat.poisson));
  const double bulk = mat.young / (3 * (1 - 2 * mat.poisson));
  const double cell = (jd.size.x / jd.nx) * (jd.size.y / jd.ny) * (jd.size.z / jd.nz);
  const double a = std::cbrt(cell);
  // edges: k = 4 G a / 3; volumes: alpha = V0 / lambda_v, lambda_v = K - 16 G / 9 > 0
  const double k = 4 * g * a / 3;
  const double lambda_v = bulk - 16 * g / 9;
  // a cell or modulus so small that k underflows to 0 (a 1e-200 m box) has no finite
  // compliance: name the inputs, not the derived field the step would refuse
  if (!(k > 0 && std::isfinite(1 / k) && std::isfinite(k)))
    throw Error("jelly_settings: JellyDef.size " + format_vec3(jd.size) + " m in " + std::to_string(jd.nx) + " x " +
                std::to_string(jd.ny) + " x " + std::to_string(jd.nz) + " cells and JellyMaterial.young " +
                format_value(mat.young) + " Pa give an edge stiffness k = 4 G a / 3 = " + format_value(k) +
                " N/m whose compliance 1 / k is not a finite number; use a larger box or a stiffer material");
  // a damping time so long that c = tau k overflows (1e300 s) would be refused as
  // SoftBodyDef.spring_damping, a field the caller never set: name the input
  if (!std::isfinite(mat.damping_time * k))
    throw Error("JellyMaterial.damping_time: " + format_value(mat.damping_time) +
                " s gives the edges the damping c = tau k = " + format_value(mat.damping_time * k) +
                " N s/m with k = " + format_value(k) +
                " N/m, not a finite number; use a shorter damping time");
  SoftBodyDef d;
  d.stretch_compliance = 1 / k;
  d.volume_compliance = (cell / 6) / lambda_v;
  d.spring_damping = mat.damping_time * k;
  // substeps: omega_max h <= 1 with omega_max^2 = 2 (d - 1) k w (Gershgorin), d = 26
  // edges at a particle where mirrored cells' diagonals meet, w = particles / mass
  const double particles = double(jd.nx + 1) * (jd.ny + 1) * (jd.nz + 1);
  const double omega = std::sqrt(2 * 25 * k * particles / jd.mass);
  const double need = std::ceil(omega * dt);
  d.substeps = static_cast<int>(std::clamp(need, 10.0, 10000.0));
  return d;
}

SoftBody SoftBody::jelly_box(const JellyDef& jd) { return jelly_box(jd, jelly_settings(jd)); }

SoftBody SoftBody::jelly_box(const JellyDef& jd, const SoftBodyDef& def) {
  // shape
  require_finite(jd.center, "JellyDef.center");
  positive(jd.size.x, "JellyDef.size.x");
  positive(jd.size.y, "JellyDef.size.y");
  positive(jd.size.z, "JellyDef.size.z");
  require_unit_quat(jd.rotation, "JellyDef.rotation");
  require_count(jd.nx, 1, 64, "JellyDef.nx");
  require_count(jd.ny, 1, 64, "JellyDef.ny");
  require_count(jd.nz, 1, 64, "JellyDef.nz");
  positive(jd.mass, "JellyDef.mass");
  require_finite(jd.velocity, "JellyDef.velocity");
  const int px = jd.nx + 1, py = jd.ny + 1, pz = jd.nz + 1;
  const std::size_t n = std::size_t(px) * py * pz;
  auto id = [&](int i, int j, int k) { return std::uint32_t((k * py + j) * px + i); };
  SoftMesh m;
  m.positions.resize(n);
  m.velocities.assign(n, jd.velocity);
  m.masses.assign(n, jd.mass / double(n));
  for (int k = 0; k < pz; ++k)
    for (int j = 0; j < py; ++j)
      for (int i = 0; i < px; ++i) {
        const Vec3 local = jd.size * (Vec3(double(i) / jd.nx, double(j) / jd.ny, double(k) / jd.nz) - 0.5);
        m.positions[id(i, j, k)] = jd.center + jd.rotation * local;
      }
  // six tetrahedra per cell about a diagonal (Freudenthal/Kuhn): for each order of the
  // axes, the path (0,0,0) -> e_p -> e_p + e_q -> (1,1,1) in the cell's own frame, which
  // is mirrored along the axes where mirrored() says so. Faces match: the diagonal of a
  // face normal to x depends only on the y and z flags, which the two cells sharing it
  // have in common (and likewise for y and z).
  const int cells[3] = {jd.nx, jd.ny, jd.nz};
  static constexpr std::array<std::array<int, 3>, 6> kPerm = {
      {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  std::set<std::pair<std::uint32_t, std::uint32_t>> edges;
  for (int k = 0; k < jd.nz; ++k)
    for (int j = 0; j < jd.ny; ++j)
      for (int i = 0; i < jd.nx; ++i)
        for (const auto& p : kPerm) {
          // the cell's mirror flags and the path's start corner
          const int cell[3] = {i, j, k};
          int c[3], step[3];
          for (int a = 0; a < 3; ++a) {
            const int f = mirrored(cell[a], cells[a]);
            c[a] = cell[a] + f;
            step[a] = f ? -1 : 1;
          }
          std::uint32_t v[4];
          v[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            c[p[s]] += step[p[s]];
            v[s + 1] = id(c[0], c[1], c[2]);
          }
          m.tets.push_back({v[0], v[1], v[2], v[3]});
          for (int a = 0; a < 4; ++a)
            for (int b = a + 1; b < 4; ++b) edges.insert({std::min(v[a], v[b]), std::max(v[a], v[b])});
        }
  for (const auto& e : edges) m.constraints.push_back({.a = e.first, .b = e.second});
  // the boundary surface as triangles (for drawing): two per boundary cell face
  auto quad = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
    m.triangles.push_back({a, b, c});
    m.triangles.push_back({a, c, d});
  };
  for (int j = 0; j < jd.ny; ++j)
    for (int i = 0; i < jd.nx; ++i) {
      quad(id(i, j, 0), id(i, j + 1, 0), id(i + 1, j + 1, 0), id(i + 1, j, 0));              // -z
      quad(id(i, j, jd.nz), id(i + 1, j, jd.nz), id(i + 1, j + 1, jd.nz), id(i, j + 1, jd.nz));  // +z
    }
  for (int k = 0; k < jd.nz; ++k)
    for (int i = 0; i < jd.nx; ++i) {
      quad(id(i, 0, k), id(i + 1, 0, k), id(i + 1, 0, k + 1), id(i, 0, k + 1));              // -y
      quad(id(i, jd.ny, k), id(i, jd.ny, k + 1), id(i + 1, jd.ny, k + 1), id(i + 1, jd.ny, k));  // +y
    }
  for (int k = 0; k < jd.nz; ++k)
    for (int j = 0; j < jd.ny; ++j) {
      quad(id(0, j, k), id(0, j, k + 1), id(0, j + 1, k + 1), id(0, j + 1, k));              // -x
      quad(id(jd.nx, j, k), id(jd.nx, j + 1, k), id(jd.nx, j + 1, k + 1), id(jd.nx, j, k + 1));  // +x
    }
  require_float_state(m, "JellyDef", "center and size");
  return from_mesh(m, def, "JellyDef");
}

}  // namespace pba
