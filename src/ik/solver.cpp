// IK solvers on a Skeleton: analytic 1-DOF and 3-DOF, CCD, the Jacobian family
// (transpose, pseudo-inverse, damped least squares, selectively damped least
// squares) and FABRIK on trees with joint limits. All work in place on the
// skeleton's structure-of-arrays pose; their workspace is sized in prepare().
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <string>

#include "ik/ik_access.h"
#include "ik/ik_math.h"
#include "pba/ik.h"

namespace pba::ik {

using A = SolverAccess;

// ---------------------------------------------------------------------------
// names, settings, support checks

std::string_view method_name(Method m) {
  switch (m) {
    case Method::analytic_1dof: return "analytic_1dof";
    case Method::analytic_3dof: return "analytic_3dof";
    case Method::two_bone: return "two_bone";
    case Method::ccd: return "ccd";
    case Method::jacobian_transpose: return "jacobian_transpose";
    case Method::pseudo_inverse: return "pseudo_inverse";
    case Method::dls: return "dls";
    case Method::sdls: return "sdls";
    case Method::fabrik: return "fabrik";
  }
  return "unknown";
}

Method parse_solver(std::string_view text, std::string_view where) {
  std::string t(text);
  for (char& c : t) {
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (c == '-') c = '_';
  }
  for (Method m : all_methods)
    if (t == method_name(m)) return m;
  if (t == "1dof") return Method::analytic_1dof;
  if (t == "3dof") return Method::analytic_3dof;
  if (t == "twobone" || t == "two_bone_ik") return Method::two_bone;
  if (t == "jt" || t == "transpose") return Method::jacobian_transpose;
  if (t == "pinv" || t == "pseudoinverse") return Method::pseudo_inverse;
  if (t == "svd" || t == "svd_dls") return Method::sdls;
  std::string list;
  for (Method m : all_methods) {
    if (!list.empty()) list += ", ";
    list += method_name(m);
  }
  throw Error(std::string(where) + ": unknown IK solver '" + std::string(text) +
              "' (expected one of " + list + ")");
}

int default_max_iterations(Method m) {
  switch (m) {
    case Method::analytic_1dof:
    case Method::analytic_3dof:
    case Method::two_bone: return 1;
    case Method::ccd: return 1000;
    case Method::jacobian_transpose: return 2000;
    case Method::pseudo_inverse: return 200;
    case Method::dls: return 1000;  // reachable targets take ~5-10; a limited chain pressed on its limits creeps
    case Method::sdls: return 300;
    case Method::fabrik: return 1000;  // free ball chains take tens (76 at 1000 bones); limited chains hand over to DLS
  }
  return 100;
}

void SolverSettings::validate(std::string_view where) const {
  const std::string w(where);
  require_count(max_iterations, 0, 100000000, w + ".max_iterations");
  require_positive(tolerance, w + ".tolerance");
  require_positive(orientation_tolerance, w + ".orientation_tolerance");
  require_non_negative(damping, w + ".damping");
  require_non_negative(max_step_angle, w + ".max_step_angle");
  require_in_range(stall_ratio, 0, 1, w + ".stall_ratio");
  require_non_negative(max_seconds, w + ".max_seconds");
  if (static_cast<int>(method) > static_cast<int>(Method::fabrik))
    throw Error(w + ".method: unknown value " + std::to_string(static_cast<int>(method)));
}

namespace {

// moving joints on the path from the root to `bone`, and the last one found
int moving_joints_on_path(const Skeleton& s, int bone, int* first_moving, JointType* type) {
  int count = 0;
  for (int j = bone; j >= 0; j = s.parents()[j])
    if (s.joint_types()[j] != JointType::fixed) {
      ++count;
      if (first_moving) *first_moving = j;
      if (type) *type = s.joint_types()[j];
    }
  return count;
}

}  // namespace

bool supports(Method m, const Skeleton& s, std::string* why) {
  auto fail = [&](std::string msg) {
    if (why) *why = std::string(method_name(m)) + ": " + msg;
    return false;
  };
  if (m != Method::analytic_1dof && m != Method::analytic_3dof && m != Method::two_bone) return true;
  if (s.effector_count() != 1)
    return fail("needs exactly one effector, got " + std::to_string(s.effector_count()));
  if (s.root_free()) return fail("needs a fixed root");
  const int bone = s.effector(0).bone;
  if (m == Method::two_bone) {
    const int parent = s.parents()[bone];
    if (s.joint_types()[bone] != JointType::hinge || parent < 0 ||
        s.joint_types()[parent] != JointType::ball)
      return fail("needs the effector's bone on a hinge (elbow) whose parent bone is on a ball joint (shoulder)");
    return true;
  }
  JointType type = JointType::fixed;
  const int count = moving_joints_on_path(s, bone, nullptr, &type);
  const JointType want = m == Method::analytic_1dof ? JointType::hinge : JointType::ball;
  if (count != 1 || type != want)
    return fail(std::string("needs exactly one moving joint, a ") +
                (want == JointType::hinge ? "hinge" : "ball joint") +
                ", between the root and the effector; found " + std::to_string(count) +
                " moving joints");
  return true;
}

// ---------------------------------------------------------------------------
// dense helpers on m x m matrices

namespace detail {

bool cholesky_solve(const double* Am, int m, double ridge, double* L, const double* b, double* x) {
  // factor A + ridge I = L L^T (lower triangle of L, row-major)
  for (int i = 0; i < m; ++i) {
    for (int j = 0; j <= i; ++j) {
      double sum = Am[i * m + j] + (i == j ? ridge : 0.0);
      for (int k = 0; k < j; ++k) sum -= L[i * m + k] * L[j * m + k];
      if (i == j) {
        if (!(sum > 0)) return false;
        L[i * m + i] = std::sqrt(sum);
      } else {
        L[i * m + j] = sum / L[j * m + j];
      }
    }
  }
  // forward then backward substitution
  for (int i = 0; i < m; ++i) {
    double sum = b[i];
    for (int k = 0; k < i; ++k) sum -= L[i * m + k] * x[k];
    x[i] = sum / L[i * m + i];
  }
  for (int i = m - 1; i >= 0; --i) {
    double sum = x[i];
    for (int k = i + 1; k < m; ++k) sum -= L[k * m + i] * x[k];
    x[i] = sum / L[i * m + i];
  }
  return true;
}

void jacobi_eigen(const double* Am, int m, double* V, double* w, double* a) {
  // start from A and V = I
  std::memcpy(a, Am, sizeof(double) * m * m);
  for (int i = 0; i < m * m; ++i) V[i] = 0;
  for (int i = 0; i < m; ++i) V[i * m + i] = 1;
  // cyclic sweeps of plane rotations zeroing off-diagonal entries
  for (int sweep = 0; sweep < 50; ++sweep) {
    double off = 0, diag = 0;
    for (int i = 0; i < m; ++i) {
      diag += a[i * m + i] * a[i * m + i];
      for (int j = i + 1; j < m; ++j) off += a[i * m + j] * a[i * m + j];
    }
    if (off <= 1e-30 * diag || off == 0) break;
    for (int p = 0; p < m; ++p) {
      for (int q = p + 1; q < m; ++q) {
        const double apq = a[p * m + q];
        if (apq == 0) continue;
        const double theta = (a[q * m + q] - a[p * m + p]) / (2 * apq);
        const double t = (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1));
        const double c = 1 / std::sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < m; ++k) {
          const double akp = a[k * m + p], akq = a[k * m + q];
          a[k * m + p] = c * akp - s * akq;
          a[k * m + q] = s * akp + c * akq;
        }
        for (int k = 0; k < m; ++k) {
          const double apk = a[p * m + k], aqk = a[q * m + k];
          a[p * m + k] = c * apk - s * aqk;
          a[q * m + k] = s * apk + c * aqk;
        }
        for (int k = 0; k < m; ++k) {
          const double vkp = V[k * m + p], vkq = V[k * m + q];
          V[k * m + p] = c * vkp - s * vkq;
          V[k * m + q] = s * vkp + c * vkq;
        }
      }
    }
  }
  for (int i = 0; i < m; ++i) w[i] = a[i * m + i];
}

PBA_CLONES Vec3 reach_pass(const Vec3& from, const Vec3* q, const double* len, Vec3* out, int count) {
  constexpr double kTiny = 1e-300;  // below this squared distance the direction is undefined
  // a direction for a step whose point coincides with its goal: the one between the goals
  // (the bone keeps the pose it had), else +X
  auto fallback = [&](int i, double& dx, double& dy, double& dz) {
    dx = q[-i].x - q[1 - i].x, dy = q[-i].y - q[1 - i].y, dz = q[-i].z - q[1 - i].z;
    double l2 = dx * dx + dy * dy + dz * dz;
    if (!(l2 > kTiny)) dx = 1, dy = 0, dz = 0, l2 = 1;
    return l2;
  };
  double px = from.x, py = from.y, pz = from.z;
  out[0] = from;
  // the first step's difference and squared distance, from the vector
  double dx = q[0].x - px, dy = q[0].y - py, dz = q[0].z - pz;
  double l2e = dx * dx + dy * dy + dz * dz;
  if (!(l2e > kTiny)) l2e = fallback(0, dx, dy, dz);
  double l2 = l2e;
  for (int i = 0;; ++i) {
    // the step: scale len / |d| as sqrt(l2) (len / l2), the division beside the root
    const double li = len[i];
    const double inv = li / l2;
    const double root = std::sqrt(l2);
    const double sc = root * inv;
    const double sx = sc * dx, sy = sc * dy, sz = sc * dz;
    const double nx = px + sx, ny = py + sy, nz = pz + sz;
    out[i + 1] = Vec3(nx, ny, nz);
    if (i + 1 == count) return out[i + 1];
    // the next difference d' = e - sc d with e = Q_{i+1} - p, and its squared length
    // |e|^2 + sc^2 |d|^2 - 2 sc (e . d), where sc^2 |d|^2 = len (len / l2) |d|^2 and
    // 2 sc (e . d) = sqrt(l2) (2 (len / l2) (e . d)): one product after the root
    const Vec3& qn = q[-(i + 1)];
    const double ex = qn.x - px, ey = qn.y - py, ez = qn.z - pz;
    const double ee = ex * ex + ey * ey + ez * ez;
    const double ed2 = 2 * (ex * dx + ey * dy + ez * dz);
    const double c = ee + inv * (li * l2e);
    dx = ex - sx, dy = ey - sy, dz = ez - sz;
    px = nx, py = ny, pz = nz;
    l2e = dx * dx + dy * dy + dz * dz;
    l2 = c - root * (inv * ed2);
    // cancellation (the new distance small next to the terms): take it from the vector
    if (!(l2 > c * (1.0 / 64))) {
      l2 = l2e;
      if (!(l2 > kTiny)) l2 = l2e = fallback(i + 1, dx, dy, dz);
    }
  }
}

PBA_CLONES void rebuild_rotations(const RebuildArgs& a) {
  // Three passes, so that the bones' independent work overlaps: in one loop, a bone's turn,
  // product and normalisation formed a dependent path of ~90 cycles in ~190 instructions,
  // about what the out-of-order window holds, so bones hardly overlapped (108 cycles per
  // bone on a chain of 10; 54 in three passes, with the square roots and divisions
  // vectorised in the second and the quaternions stored component by component).
  // 1. each bone's world rotation turned by the shortest arc from its old direction (the x
  //    column of the old rotation, unit) to its new one (unit: the bone is its length long
  //    by construction). The turn (1 + c, a x b) is 2 cos(angle / 2) times a unit
  //    quaternion: the product with the old rotation is normalised once, in pass 2.
  for (int k = 0; k < a.count; ++k) {
    const int i = a.bones[k];
    const Quat w0 = a.world[i];
    const double yy = w0.y * w0.y, zz = w0.z * w0.z;
    const double ax = 1 - 2 * (yy + zz), ay = 2 * (w0.x * w0.y + w0.w * w0.z), az = 2 * (w0.x * w0.z - w0.w * w0.y);
    const double il = a.inv_len[i];
    const Vec3& t0 = a.points ? a.points[k + 1] : a.tip[i];
    const Vec3& s0 = a.points ? a.points[k] : a.start[i];
    const double bx = (t0.x - s0.x) * il, by = (t0.y - s0.y) * il, bz = (t0.z - s0.z) * il;
    const double c = ax * bx + ay * by + az * bz;
    Quat w;
    if (c > -1 + 1e-12) {
      const double tw = 1 + c, tx = ay * bz - az * by, ty = az * bx - ax * bz, tz = ax * by - ay * bx;
      w = Quat(tw * w0.w - tx * w0.x - ty * w0.y - tz * w0.z, tw * w0.x + tx * w0.w + ty * w0.z - tz * w0.y,
               tw * w0.y - tx * w0.z + ty * w0.w + tz * w0.x, tw * w0.z + tx * w0.y - ty * w0.x + tz * w0.w);
    } else {
      w = qmul(from_to(Vec3(ax, ay, az), Vec3(bx, by, bz)), w0);
    }
    put(a.world[i], w);
    a.scratch[k] = w.w * w.w + w.x * w.x + w.y * w.y + w.z * w.z;
  }
  // 2. the normalising factors 1 / sqrt(n2) = sqrt(n2) (1 / n2), on a contiguous array
  for (int k = 0; k < a.count; ++k) a.scratch[k] = std::sqrt(a.scratch[k]) * (1 / a.scratch[k]);
  // 3. normalise; the joint rotation is conj(frame) world; forward kinematics of the bone.
  //    Quaternions are stored component by component (detail::put).
  if (a.chain) {
    // bone k is bone k - 1's child: the parent's new rotation and tip stay in registers
    Quat base = a.root_rotation;
    Vec3 st = a.root;
    for (int i = 0; i < a.count; ++i) {
      const double nk = a.scratch[i];
      const Quat& wu = a.world[i];
      const Quat w(wu.w * nk, wu.x * nk, wu.y * nk, wu.z * nk);
      put(a.world[i], w);
      const Quat F = a.rest_identity[i] ? base : qmul(base, a.rest[i]);
      // both factors are unit to rounding, so the product is too (no drift: world is
      // renormalised every solve)
      put(a.q[i], qmul(Quat(F.w, -F.x, -F.y, -F.z), w));
      a.start[i] = st;
      st = st + rotate_x(w, a.lengths[i]);
      a.tip[i] = st;
      base = w;
    }
    return;
  }
  for (int k = 0; k < a.count; ++k) {
    const int i = a.bones[k];
    const double nk = a.scratch[k];
    const Quat& wu = a.world[i];
    const Quat w(wu.w * nk, wu.x * nk, wu.y * nk, wu.z * nk);
    put(a.world[i], w);
    const int p = a.parents[i];
    const Quat base = p >= 0 ? a.world[p] : a.root_rotation;
    const Quat F = a.rest_identity[i] ? base : qmul(base, a.rest[i]);
    put(a.q[i], qmul(Quat(F.w, -F.x, -F.y, -F.z), w));
    const Vec3 st = p >= 0 ? a.tip[p] : a.root;
    a.start[i] = st;
    a.tip[i] = st + rotate_x(w, a.lengths[i]);
  }
}

}  // namespace detail

// ---------------------------------------------------------------------------
// the solver

struct Solver::Impl {
  Skeleton* sk = nullptr;
  SolverSettings set;
  std::uint64_t prepared_version = ~std::uint64_t(0);
  bool has_deadline = false;             // SolverSettings::max_seconds > 0 for this solve
  std::chrono::steady_clock::time_point deadline;  // ... and when it ends
  int active_count = 0;                  // active bones (sets how often the clock is read)
  std::uint64_t supported_version = ~std::uint64_t(0);  // effectors for which supports() held
  Method supported_method = Method::fabrik;              // ... with this method

  // effector structure (rebuilt when effectors change)
  int n = 0, ne = 0;
  std::vector<std::uint8_t> active;      // bone is an effector's bone or one of its ancestors
  std::vector<int> active_rev;           // active bones, children before parents
  std::vector<int> active_fwd;           // active bones, parents before children
  bool all_free_balls = false;           // every active joint is an unlimited ball (FABRIK on positions)
  bool simple_chain = false;             // bone i is bone i - 1's child, every bone active
  double path_reach = 0;                 // summed length of the active bones (m): one effector's reach
  std::vector<int> eff_off, eff_list;    // effectors on each bone
  std::vector<int> under_off, under;     // effectors in each bone's subtree
  std::vector<int> path_off, path;       // each effector's bones up to the root
  std::vector<std::uint8_t> rest_identity;
  std::vector<Vec3> hx, hy;              // hinge: local in-plane basis (x = bone axis projected)
  std::vector<int> hinge_child;          // ball bone's single active child when that is a hinge, else -1

  // Jacobian workspace: m rows, ncols columns, column-major J
  int m = 0, ncols = 0;
  std::vector<int> col_of;               // first column of each bone's joint, -1 if none
  std::vector<int> row_of, ori_row_of;   // rows of each effector (-1: no orientation rows)
  std::vector<double> J, Amat, L, V, w, work, e, y, t, dtheta, v, rho;
  // one position effector (3 rows): J is never stored, only each joint's vector (see build_compact)
  bool compact = false;
  std::vector<Vec3> jd;

  // FABRIK and CCD workspace
  std::vector<Vec3> goal, acc, eff_pos, cp, fw;  // fw: FABRIK stage 1 points, target first
  std::vector<double> cl, clr, inv_len;           // chain lengths forward, reversed; 1 / length
  std::vector<double> scratch;                    // n doubles for detail::rebuild_rotations
  std::vector<Quat> saved_q;
  std::vector<double> saved_angle;
  Vec3 saved_root{0};
  std::vector<double> accw;

  explicit Impl(Skeleton& s, const SolverSettings& st) : sk(&s), set(st) { prepare(); }

  int max_iterations() const {
    return set.max_iterations > 0 ? set.max_iterations : default_max_iterations(set.method);
  }

  // size the workspace for the skeleton's current effectors (allocates)
  void prepare() {
    Skeleton& s = *sk;
    if (prepared_version == s.effector_version()) return;
    prepared_version = s.effector_version();
    n = s.bone_count();
    ne = s.effector_count();
    const auto parents = s.parents();

    // effectors per bone, active bones and per-effector paths
    active.assign(n, 0);
    std::vector<int> count(n + 1, 0);
    for (int k = 0; k < ne; ++k) count[s.effector(k).bone + 1]++;
    eff_off.assign(n + 1, 0);
    for (int i = 0; i < n; ++i) eff_off[i + 1] = eff_off[i] + count[i + 1];
    eff_list.assign(ne, 0);
    std::vector<int> fill(eff_off.begin(), eff_off.end() - 1);
    for (int k = 0; k < ne; ++k) eff_list[fill[s.effector(k).bone]++] = k;
    path_off.assign(ne + 1, 0);
    path.clear();
    std::vector<int> under_count(n, 0);
    for (int k = 0; k < ne; ++k) {
      for (int j = s.effector(k).bone; j >= 0; j = parents[j]) {
        path.push_back(j);
        active[j] = 1;
        under_count[j]++;
      }
      path_off[k + 1] = static_cast<int>(path.size());
    }
    under_off.assign(n + 1, 0);
    for (int i = 0; i < n; ++i) under_off[i + 1] = under_off[i] + under_count[i];
    under.assign(under_off[n], 0);
    std::vector<int> ufill(under_off.begin(), under_off.end() - 1);
    for (int k = 0; k < ne; ++k)
      for (int p = path_off[k]; p < path_off[k + 1]; ++p) under[ufill[path[p]]++] = k;
    active_rev.clear();
    for (int i = n - 1; i >= 0; --i)
      if (active[i]) active_rev.push_back(i);
    active_fwd.assign(active_rev.rbegin(), active_rev.rend());

    // per-bone constants
    rest_identity.assign(n, 0);
    hx.assign(n, Vec3(1, 0, 0));
    hy.assign(n, Vec3(0, 1, 0));
    for (int i = 0; i < n; ++i) {
      const Quat r = A::rest(s)[i];
      rest_identity[i] = r.w == 1 && r.x == 0 && r.y == 0 && r.z == 0;
      if (s.joint_types()[i] == JointType::hinge) {
        const Vec3 a = A::axis(s)[i];
        Vec3 xp = Vec3(1, 0, 0) - a.x * a;
        const double l = glm::length(xp);
        hx[i] = l > 1e-9 ? xp / l : Vec3(0);  // zero: the hinge only twists the bone
        hy[i] = glm::cross(a, hx[i]);
      }
    }

    // a ball joint with exactly one active child, a hinge: FABRIK solves its twist
    hinge_child.assign(n, -1);
    {
      std::vector<int> active_children(n, 0), last_child(n, -1);
      for (int i = 0; i < n; ++i)
        if (active[i] && parents[i] >= 0) active_children[parents[i]]++, last_child[parents[i]] = i;
      for (int i = 0; i < n; ++i)
        if (active[i] && s.joint_types()[i] == JointType::ball && active_children[i] == 1 &&
            s.joint_types()[last_child[i]] == JointType::hinge && glm::length(hx[last_child[i]]) > 0)
          hinge_child[i] = last_child[i];
    }

    // Jacobian layout: 3 rows per effector (+3 with an orientation target),
    // a column per joint DOF on some effector's path (+3 for a free root)
    m = 0;
    row_of.assign(ne, 0);
    ori_row_of.assign(ne, -1);
    for (int k = 0; k < ne; ++k) {
      row_of[k] = m;
      m += 3;
    }
    for (int k = 0; k < ne; ++k)
      if (s.effector(k).orientation) {
        ori_row_of[k] = m;
        m += 3;
      }
    ncols = s.root_free() ? 3 : 0;
    col_of.assign(n, -1);
    for (int i = 0; i < n; ++i) {
      if (!active[i]) continue;
      const JointType jt = s.joint_types()[i];
      if (jt == JointType::hinge) col_of[i] = ncols, ncols += 1;
      else if (jt == JointType::ball) col_of[i] = ncols, ncols += 3;
    }
    // orientation targets can be added or removed without a version bump, so size for all
    int mmax = 6 * ne;
    J.assign(static_cast<std::size_t>(mmax) * std::max(ncols, 1), 0.0);
    Amat.assign(mmax * mmax, 0.0);
    L.assign(mmax * mmax, 0.0);
    V.assign(mmax * mmax, 0.0);
    work.assign(mmax * mmax, 0.0);
    w.assign(mmax, 0.0);
    e.assign(mmax, 0.0);
    y.assign(mmax, 0.0);
    t.assign(mmax, 0.0);
    dtheta.assign(std::max(ncols, 1), 0.0);
    v.assign(std::max(ncols, 1), 0.0);
    rho.assign(std::max(ncols, 1), 0.0);
    jd.assign(n, Vec3(0));
    goal.assign(n, Vec3(0));
    acc.assign(n, Vec3(0));
    accw.assign(n, 0.0);
    eff_pos.assign(std::max(ne, 1), Vec3(0));
    cp.assign(n + 1, Vec3(0));
    fw.assign(n + 1, Vec3(0));
    cl.assign(n, 0.0);
    clr.assign(n, 0.0);
    inv_len.assign(n, 0.0);
    scratch.assign(n, 0.0);
    for (int i = 0; i < n; ++i) inv_len[i] = 1 / s.lengths()[i];
    // the lengths along active_fwd (a chain when there is one effector), forward and reversed
    const int na = static_cast<int>(active_fwd.size());
    active_count = na;
    path_reach = 0;
    for (int k = 0; k < na; ++k) {
      cl[k] = s.lengths()[active_fwd[k]];
      clr[na - 1 - k] = cl[k];
      path_reach += cl[k];
    }
    // one chain in stored order (bone i the child of bone i - 1, every bone active)
    simple_chain = na == n;
    for (int i = 0; i < n; ++i)
      if (parents[i] != i - 1) simple_chain = false;
    // FABRIK iterates on positions only when every active joint is an unlimited ball
    all_free_balls = true;
    for (int j : active_rev)
      if (s.joint_types()[j] != JointType::ball || A::limited(s)[j]) all_free_balls = false;
    saved_q.assign(n, Quat(1, 0, 0, 0));
    saved_angle.assign(n, 0.0);
  }

  // orientation rows may appear later (set_orientation_target): recompute row layout, no allocation
  void layout_rows() {
    m = 3 * ne;
    for (int k = 0; k < ne; ++k) {
      if (sk->effector(k).orientation) {
        ori_row_of[k] = m;
        m += 3;
      } else {
        ori_row_of[k] = -1;
      }
    }
  }

  Quat frame(int i) const {
    const Skeleton& s = *sk;
    const int p = s.parents()[i];
    const Quat base = p >= 0 ? s.world_rotations()[p] : s.root_rotation();
    return rest_identity[i] ? base : detail::qmul(base, A::rest(s)[i]);
  }

  // residuals after forward kinematics
  void measure(SolveResult& r) const {
    const Skeleton& s = *sk;
    r.residual = 0;
    r.orientation_residual = 0;
    for (int k = 0; k < ne; ++k) {
      const EffectorDef& ef = s.effector(k);
      r.residual = std::max(r.residual, glm::length(s.tips()[ef.bone] - ef.target));
      if (ef.orientation) {
        const Quat d = *ef.orientation * glm::conjugate(s.world_rotations()[ef.bone]);
        r.orientation_residual = std::max(r.orientation_residual, glm::length(detail::quat_log(d)));
      }
    }
    // CCD and the analytic solvers handle positions only: orientation targets are reported, not required
    const bool orients = set.method == Method::fabrik || set.method == Method::dls ||
                         set.method == Method::sdls || set.method == Method::pseudo_inverse ||
                         set.method == Method::jacobian_transpose;
    r.converged = r.residual <= set.tolerance &&
                  (!orients || r.orientation_residual <= set.orientation_tolerance);
  }

  bool stalled(double prev, double now) const {
    return std::abs(prev - now) <= set.stall_ratio * std::max(now, 1e-300);
  }

  // the time budget: whether SolverSettings::max_seconds is spent, read from the clock on
  // every iteration from 64 active bones on and every 8th below (a read costs ~60 ns)
  bool out_of_time(int iteration, SolveResult& r) const {
    if (!has_deadline || (active_count < 64 && iteration % 8 != 0)) return false;
    if (std::chrono::steady_clock::now() < deadline) return false;
    r.out_of_time = true;
    return true;
  }

  // A solve that creeps (pressed against joint limits, or circling a target outside the
  // reachable set in ever smaller steps) improves each iteration by more than stall_ratio
  // yet gets nowhere: once per `window` iterations (rejected Levenberg-Marquardt steps
  // included), it stops when the error fell by less than `ratio` since the last check.
  // A converging DLS solve gains far more than 1% in 16 iterations (at least linearly);
  // CCD, which can plateau for a while before it finds its way, gets 0.1% in 64.
  struct Creep {
    double checkpoint;
    int window = 16;
    double ratio = 1e-2;
    int next = window;
    bool operator()(int iterations, double residual) {
      if (iterations < next) return false;
      next = iterations + window;
      if (residual > (1 - ratio) * checkpoint) return true;
      checkpoint = residual;
      return false;
    }
  };

  // -------------------------------------------------------------------------
  // analytic: one hinge aims the effector at the target (workbook 2.3, ik_1dof):
  // the angle between v1 = e - p and v2 = t - p, projected on the hinge plane,
  // is atan2(axis . (v1 x v2), v1 . v2)
  void analytic_1dof(SolveResult& r) {
    Skeleton& s = *sk;
    const EffectorDef& ef = s.effector(0);
    int j = -1;
    moving_joints_on_path(s, ef.bone, &j, nullptr);
    const Vec3 a = detail::rotate(frame(j), A::axis(s)[j]);
    const Vec3 p = s.starts()[j];
    Vec3 v1 = s.tips()[ef.bone] - p, v2 = ef.target - p;
    v1 -= glm::dot(v1, a) * a;
    v2 -= glm::dot(v2, a) * a;
    if (glm::dot(v1, v1) > 1e-300 && glm::dot(v2, v2) > 1e-300) {
      const double delta = std::atan2(glm::dot(a, glm::cross(v1, v2)), glm::dot(v1, v2));
      A::angle(s)[j] += delta;
      A::clamp_joint(s, j);
    }
    s.forward_kinematics();
    r.iterations = 1;
  }

  // analytic: one ball joint aims the effector with the shortest-arc rotation from v1 to v2
  void analytic_3dof(SolveResult& r) {
    Skeleton& s = *sk;
    const EffectorDef& ef = s.effector(0);
    int j = -1;
    moving_joints_on_path(s, ef.bone, &j, nullptr);
    const Quat F = frame(j);
    const Vec3 p = s.starts()[j];
    const Quat d = detail::from_to(s.tips()[ef.bone] - p, ef.target - p);
    A::q(s)[j] = glm::conjugate(F) * d * F * A::q(s)[j];
    A::clamp_joint(s, j);
    s.forward_kinematics();
    r.iterations = 1;
  }

  // -------------------------------------------------------------------------
  // CCD, workbook Algorithm 1: visit joints from the effector toward the root, turning
  // each so the effector moves toward the target; repeat until within the threshold or
  // the iteration cap. One iteration is one sweep over the chain.
  void ccd(SolveResult& r) {
    Skeleton& s = *sk;
    const int cap = max_iterations();
    const auto parents = s.parents();
    const auto types = s.joint_types();
    const double tol = set.tolerance;
    double prev = r.residual;
    for (int k = 0; k < ne; ++k) eff_pos[k] = s.tips()[s.effector(k).bone];
    Creep creep{r.residual, 64, 1e-3};
    for (int it = 0; it < cap && !r.converged && !out_of_time(it, r); ++it) {
      bool done = false;
      for (int j : active_rev) {
        if (types[j] == JointType::fixed) continue;
        const Vec3 p = s.starts()[j];
        const int u0 = under_off[j], u1 = under_off[j + 1];
        Quat dR(1, 0, 0, 0);
        if (types[j] == JointType::hinge) {
          // best angle about the world hinge axis, summed over the effectors below
          const Quat F = frame(j);
          const Vec3 a = detail::rotate(F, A::axis(s)[j]);
          double sn = 0, cs = 0;
          for (int u = u0; u < u1; ++u) {
            const int k = under[u];
            const double wk = s.effector(k).weight;
            const Vec3 v1 = eff_pos[k] - p, v2 = s.effector(k).target - p;
            sn += wk * glm::dot(a, glm::cross(v1, v2));
            cs += wk * (glm::dot(v1, v2) - glm::dot(v1, a) * glm::dot(v2, a));
          }
          if (sn == 0 && cs >= 0) continue;
          const double old = A::angle(s)[j];
          A::angle(s)[j] = old + std::atan2(sn, cs);
          A::clamp_joint(s, j);
          double delta = A::angle(s)[j] - old;
          if (delta == 0) continue;
          dR = glm::angleAxis(delta, a);
        } else {
          // shortest arc from (effector - pivot) to (target - pivot); several effectors
          // below average their rotation vectors by weight
          const Quat F = frame(j);
          Quat rot(1, 0, 0, 0);
          if (u1 - u0 == 1) {
            const int k = under[u0];
            rot = detail::from_to(eff_pos[k] - p, s.effector(k).target - p);
          } else {
            Vec3 om(0);
            double ws = 0;
            for (int u = u0; u < u1; ++u) {
              const int k = under[u];
              const double wk = s.effector(k).weight;
              om += wk * detail::quat_log(detail::from_to(eff_pos[k] - p, s.effector(k).target - p));
              ws += wk;
            }
            rot = detail::quat_exp(om / ws);
          }
          const Quat old = A::q(s)[j];
          A::q(s)[j] = glm::conjugate(F) * rot * F * old;
          A::clamp_joint(s, j);
          dR = glm::normalize(F * A::q(s)[j] * glm::conjugate(old) * glm::conjugate(F));
        }
        // carry the effectors below along with the joint's turn
        for (int u = u0; u < u1; ++u) {
          const int k = under[u];
          eff_pos[k] = p + detail::rotate(dR, eff_pos[k] - p);
        }
        // workbook Algorithm 1 tests the threshold after every joint
        if (ne == 1 && glm::length(eff_pos[0] - s.effector(0).target) < tol) {
          done = true;
          break;
        }
        // the joint's own world frame is stale now; parents' frames are still valid
      }
      // a free root translates by the weighted mean error
      if (s.root_free() && !done) {
        Vec3 d(0);
        double ws = 0;
        for (int k = 0; k < ne; ++k) {
          d += s.effector(k).weight * (s.effector(k).target - eff_pos[k]);
          ws += s.effector(k).weight;
        }
        A::root_position(s) += d / ws;
      }
      s.forward_kinematics();
      for (int k = 0; k < ne; ++k) eff_pos[k] = s.tips()[s.effector(k).bone];
      r.iterations = it + 1;
      measure(r);
      if (!r.converged && (stalled(prev, r.residual) || creep(r.iterations, r.residual))) break;
      prev = r.residual;
    }
  }

  // -------------------------------------------------------------------------
  // Jacobian family (Buss 2004, "Introduction to Inverse Kinematics with Jacobian
  // Transpose, Pseudoinverse and Damped Least Squares methods"). Columns are
  // r_j x (e - p_j) for a hinge (r_j its world axis), the three world axes for a
  // ball joint, identity for a free root. J is m x ncols; only J J^T (m x m) is
  // ever formed, so the cost per iteration is linear in the DOF count.

  double largest_reach() const {
    double L = 0;
    for (int k = 0; k < ne; ++k) L = std::max(L, sk->reach(sk->effector(k).bone));
    return L;
  }

  // fill J and e (error, clamped per effector to `clamp` metres), weighted rows
  void build_jacobian(double clamp, double ori_scale) {
    Skeleton& s = *sk;
    const auto types = s.joint_types();
    std::fill(J.begin(), J.begin() + static_cast<std::size_t>(m) * ncols, 0.0);
    for (int k = 0; k < ne; ++k) {
      const EffectorDef& ef = s.effector(k);
      const double wk = ef.weight;
      const Vec3 ep = s.tips()[ef.bone];
      // position error, clamped (Buss 2004 sec. 7: clamp the target distance)
      Vec3 err = ef.target - ep;
      const double len = glm::length(err);
      if (len > clamp) err *= clamp / len;
      const int r0 = row_of[k];
      e[r0] = wk * err.x, e[r0 + 1] = wk * err.y, e[r0 + 2] = wk * err.z;
      const int o0 = ori_row_of[k];
      if (o0 >= 0) {
        Vec3 oe = detail::quat_log(*ef.orientation * glm::conjugate(s.world_rotations()[ef.bone]));
        const double ol = glm::length(oe);
        if (ol > 0.5) oe *= 0.5 / ol;
        e[o0] = wk * ori_scale * oe.x, e[o0 + 1] = wk * ori_scale * oe.y, e[o0 + 2] = wk * ori_scale * oe.z;
      }
      // a free root translates every effector one for one
      if (s.root_free()) {
        J[0 * m + r0] = wk;
        J[1 * m + r0 + 1] = wk;
        J[2 * m + r0 + 2] = wk;
      }
      // the joints on this effector's path
      for (int pi = path_off[k]; pi < path_off[k + 1]; ++pi) {
        const int j = path[pi];
        const int c = col_of[j];
        if (c < 0) continue;
        const Vec3 d = ep - s.starts()[j];
        double* col = &J[static_cast<std::size_t>(c) * m];
        if (types[j] == JointType::hinge) {
          const Vec3 a = detail::rotate(frame(j), A::axis(s)[j]);
          const Vec3 g = glm::cross(a, d);
          col[r0] = wk * g.x, col[r0 + 1] = wk * g.y, col[r0 + 2] = wk * g.z;
          if (o0 >= 0) {
            const double f = wk * ori_scale;
            col[o0] = f * a.x, col[o0 + 1] = f * a.y, col[o0 + 2] = f * a.z;
          }
        } else {
          // x-axis column: (1,0,0) x d = (0, -dz, dy); y: (dz, 0, -dx); z: (-dy, dx, 0)
          double* cx = col;
          double* cy = col + m;
          double* cz = col + 2 * m;
          cx[r0] = 0, cx[r0 + 1] = -wk * d.z, cx[r0 + 2] = wk * d.y;
          cy[r0] = wk * d.z, cy[r0 + 1] = 0, cy[r0 + 2] = -wk * d.x;
          cz[r0] = -wk * d.y, cz[r0 + 1] = wk * d.x, cz[r0 + 2] = 0;
          if (o0 >= 0) {
            const double f = wk * ori_scale;
            cx[o0] = f;
            cy[o0 + 1] = f;
            cz[o0 + 2] = f;
          }
        }
      }
    }
  }

  // zero the columns of hinges held at a limit that the error pushes further out,
  // so the other joints take over (a projected gradient step)
  void drop_saturated_columns() {
    Skeleton& s = *sk;
    const auto types = s.joint_types();
    for (int j : active_rev) {
      if (types[j] != JointType::hinge || !A::limited(s)[j]) continue;
      const double ang = A::angle(s)[j];
      const bool at_lo = ang <= A::lo(s)[j] + 1e-12, at_hi = ang >= A::hi(s)[j] - 1e-12;
      if (!at_lo && !at_hi) continue;
      double* col = &J[static_cast<std::size_t>(col_of[j]) * m];
      double g = 0;
      for (int r = 0; r < m; ++r) g += col[r] * e[r];
      if ((at_hi && g > 0) || (at_lo && g < 0))
        for (int r = 0; r < m; ++r) col[r] = 0;
    }
  }

  // One position effector, the rows of J are never formed: a ball joint's 3 x 3 block is
  // v -> v x D with D = w (e - p_j) (the columns are the world axes crossed with D), so its
  // share of J J^T is |D|^2 I - D D^T and of J^T y is D x y; a hinge's column is
  // g = w (a_j x (e - p_j)), its share g g^T and g . y; a free root's block is w I. Fills
  // e (the clamped, weighted error), Amat (J J^T) and jd (D or g per joint) in one pass over
  // the effector's path, dropping saturated hinges as drop_saturated_columns does.
  void build_compact(double clamp) {
    Skeleton& s = *sk;
    const auto types = s.joint_types();
    const auto starts = s.starts();
    const EffectorDef& ef = s.effector(0);
    const double wk = ef.weight;
    const Vec3 ep = s.tips()[ef.bone];
    // position error, clamped (Buss 2004 sec. 7: clamp the target distance)
    Vec3 err = ef.target - ep;
    const double len = glm::length(err);
    if (len > clamp) err *= clamp / len;
    const Vec3 ew = wk * err;
    e[0] = ew.x, e[1] = ew.y, e[2] = ew.z;
    double a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0;
    if (s.root_free()) a00 = a11 = a22 = wk * wk;
    const auto& limited = A::limited(s);
    for (int pi = path_off[0]; pi < path_off[1]; ++pi) {
      const int j = path[pi];
      if (col_of[j] < 0) continue;
      const Vec3 D = wk * (ep - starts[j]);
      if (types[j] == JointType::ball) {
        const double xx = D.x * D.x, yy = D.y * D.y, zz = D.z * D.z;
        a00 += yy + zz, a11 += xx + zz, a22 += xx + yy;
        a01 -= D.x * D.y, a02 -= D.x * D.z, a12 -= D.y * D.z;
        jd[j] = D;
      } else {
        Vec3 g = glm::cross(detail::rotate(frame(j), A::axis(s)[j]), D);
        // a hinge held at a limit that the error pushes further out takes no part
        if (limited[j]) {
          const double ang = A::angle(s)[j], gd = glm::dot(g, ew);
          if ((ang >= A::hi(s)[j] - 1e-12 && gd > 0) || (ang <= A::lo(s)[j] + 1e-12 && gd < 0)) g = Vec3(0);
        }
        a00 += g.x * g.x, a01 += g.x * g.y, a02 += g.x * g.z;
        a11 += g.y * g.y, a12 += g.y * g.z, a22 += g.z * g.z;
        jd[j] = g;
      }
    }
    Amat[0] = a00, Amat[1] = a01, Amat[2] = a02;
    Amat[3] = a01, Amat[4] = a11, Amat[5] = a12;
    Amat[6] = a02, Amat[7] = a12, Amat[8] = a22;
  }

  // dtheta = J^T x from the vectors build_compact kept
  void jt_times_compact(const double* x) {
    Skeleton& s = *sk;
    const auto types = s.joint_types();
    const Vec3 y3(x[0], x[1], x[2]);
    if (s.root_free()) {
      const double wk = s.effector(0).weight;
      dtheta[0] = wk * x[0], dtheta[1] = wk * x[1], dtheta[2] = wk * x[2];
    }
    for (int pi = path_off[0]; pi < path_off[1]; ++pi) {
      const int j = path[pi];
      const int c = col_of[j];
      if (c < 0) continue;
      if (types[j] == JointType::ball) {
        const Vec3 r = glm::cross(jd[j], y3);
        dtheta[c] = r.x, dtheta[c + 1] = r.y, dtheta[c + 2] = r.z;
      } else {
        dtheta[c] = glm::dot(jd[j], y3);
      }
    }
  }

  // A = J J^T (m x m, symmetric): the only matrix product formed
  void gram() {
    std::fill(Amat.begin(), Amat.begin() + m * m, 0.0);
    if (m == 3) {
      double a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0;
      for (int c = 0; c < ncols; ++c) {
        const double* col = &J[static_cast<std::size_t>(c) * 3];
        a00 += col[0] * col[0], a01 += col[0] * col[1], a02 += col[0] * col[2];
        a11 += col[1] * col[1], a12 += col[1] * col[2], a22 += col[2] * col[2];
      }
      Amat[0] = a00, Amat[1] = a01, Amat[2] = a02;
      Amat[3] = a01, Amat[4] = a11, Amat[5] = a12;
      Amat[6] = a02, Amat[7] = a12, Amat[8] = a22;
      return;
    }
    for (int c = 0; c < ncols; ++c) {
      const double* col = &J[static_cast<std::size_t>(c) * m];
      for (int i = 0; i < m; ++i) {
        const double ci = col[i];
        if (ci == 0) continue;
        for (int k = i; k < m; ++k) Amat[i * m + k] += ci * col[k];
      }
    }
    for (int i = 0; i < m; ++i)
      for (int k = 0; k < i; ++k) Amat[i * m + k] = Amat[k * m + i];
  }

  // dtheta = J^T x
  void jt_times(const double* x) {
    if (compact) {
      jt_times_compact(x);
      return;
    }
    for (int c = 0; c < ncols; ++c) {
      const double* col = &J[static_cast<std::size_t>(c) * m];
      double sum = 0;
      for (int r = 0; r < m; ++r) sum += col[r] * x[r];
      dtheta[c] = sum;
    }
  }

  // scale dtheta so no entry exceeds `cap` (rad or m)
  static void clamp_max_abs(double* x, int count, double cap) {
    double mx = 0;
    for (int i = 0; i < count; ++i) mx = std::max(mx, std::abs(x[i]));
    if (mx > cap) {
      const double f = cap / mx;
      for (int i = 0; i < count; ++i) x[i] *= f;
    }
  }

  // apply dtheta to the pose, projecting every joint into its limits; with `save`, the
  // joint values it changes go to saved_q / saved_angle first (for restore_pose)
  void apply_dtheta(bool save) {
    Skeleton& s = *sk;
    const auto types = s.joint_types();
    const auto& limited = A::limited(s);
    auto& q = A::q(s);
    auto& angle = A::angle(s);
    saved_root = A::root_position(s);
    if (s.root_free()) A::root_position(s) += Vec3(dtheta[0], dtheta[1], dtheta[2]);
    for (int j : active_rev) {
      const int c = col_of[j];
      if (c < 0) continue;
      if (save) detail::put(saved_q[j], q[j]), saved_angle[j] = angle[j];
      if (types[j] == JointType::hinge) {
        angle[j] += dtheta[c];
        A::clamp_joint(s, j);
        continue;
      }
      // world rotation vector -> joint frame; q <- exp(w_local) q
      // (1, w/2) normalised turns by 2 atan(|w|/2) = |w| + O(|w|^3) about w, without trigonometry
      const Vec3 om = detail::rotate_inv(frame(j), Vec3(dtheta[c], dtheta[c + 1], dtheta[c + 2]));
      const Quat qn = detail::qmul(Quat(1, 0.5 * om.x, 0.5 * om.y, 0.5 * om.z), q[j]);
      if (limited[j]) {
        detail::put(q[j], qn);
        A::clamp_joint(s, j);
      } else {
        // an unlimited ball joint only needs the normalisation
        detail::put(q[j], qn * (1 / std::sqrt(qn.w * qn.w + qn.x * qn.x + qn.y * qn.y + qn.z * qn.z)));
      }
    }
  }

  // Buss and Kim (2005), "Selectively damped least squares for inverse kinematics":
  // J = U S V^T from the eigen-decomposition of the m x m J J^T (v_i = J^T u_i / s_i);
  // each singular direction's step is clamped by gamma_i = gamma_max min(1, N_i / M_i).
  void sdls_step(double gamma_max) {
    detail::jacobi_eigen(Amat.data(), m, V.data(), w.data(), work.data());
    double wmax = 0;
    for (int i = 0; i < m; ++i) wmax = std::max(wmax, w[i]);
    std::fill(dtheta.begin(), dtheta.begin() + ncols, 0.0);
    // rho_j = sum over effectors of |3-row block of column j|
    for (int c = 0; c < ncols; ++c) {
      const double* col = &J[static_cast<std::size_t>(c) * m];
      double sum = 0;
      for (int r = 0; r < m; r += 3)
        sum += std::sqrt(col[r] * col[r] + col[r + 1] * col[r + 1] + col[r + 2] * col[r + 2]);
      rho[c] = sum;
    }
    for (int i = 0; i < m; ++i) {
      if (!(w[i] > 1e-12 * wmax) || w[i] <= 0) continue;
      const double sigma = std::sqrt(w[i]);
      // u_i (column i of V), alpha_i = u_i . e, N_i = sum of block norms of u_i
      double alpha = 0, N = 0;
      for (int r = 0; r < m; ++r) {
        y[r] = V[r * m + i];
        alpha += y[r] * e[r];
      }
      for (int r = 0; r < m; r += 3) N += std::sqrt(y[r] * y[r] + y[r + 1] * y[r + 1] + y[r + 2] * y[r + 2]);
      // v_i = J^T u_i / sigma_i and M_i = sum_j |v_ij| rho_j / sigma_i
      double M = 0;
      for (int c = 0; c < ncols; ++c) {
        const double* col = &J[static_cast<std::size_t>(c) * m];
        double sum = 0;
        for (int r = 0; r < m; ++r) sum += col[r] * y[r];
        v[c] = sum / sigma;
        M += std::abs(v[c]) * rho[c];
      }
      M /= sigma;
      const double gamma = gamma_max * std::min(1.0, M > 0 ? N / M : 1.0);
      // phi_i = clamp(alpha_i / sigma_i v_i, gamma_i)
      const double f = alpha / sigma;
      double mx = 0;
      for (int c = 0; c < ncols; ++c) mx = std::max(mx, std::abs(f * v[c]));
      const double g = mx > gamma ? gamma / mx : 1.0;
      for (int c = 0; c < ncols; ++c) dtheta[c] += g * f * v[c];
    }
    clamp_max_abs(dtheta.data(), ncols, gamma_max);
  }

  // the Jacobian methods' loop; `meth` is set.method, or dls when FABRIK hands over its
  // last iterations (iterations then count on from r.iterations)
  void jacobian(SolveResult& r, Method meth) {
    Skeleton& s = *sk;
    layout_rows();
    const int cap = max_iterations();
    const double reach = std::max(largest_reach(), 1e-9);
    // per-effector error clamp and orientation row scale (m per rad)
    const double clamp = (meth == Method::jacobian_transpose ? 1.0 : 0.3) * reach;
    const double ori_scale = reach;
    const double lambda0 = (set.damping > 0 ? set.damping : 0.02) * reach;
    double lambda = lambda0;
    const double step_cap = set.max_step_angle > 0 ? set.max_step_angle
                            : meth == Method::sdls ? kPi / 4
                                                   : 0.5;
    double prev = r.residual;
    // dls and sdls only accept steps that lower the cost (Levenberg-Marquardt): a rejected
    // step is undone and retried with more damping (dls) or a shorter cap (sdls), so an
    // unreachable target or a singular pose cannot make the pose oscillate
    const bool monotone = meth == Method::dls || meth == Method::sdls;
    double gamma = step_cap;
    double prev_cost = monotone ? cost(ori_scale) : 0.0;
    compact = m == 3 && meth != Method::sdls;
    Creep creep{r.residual, 16, 1e-2, r.iterations + 16};
    for (int it = r.iterations; it < cap && !r.converged && !out_of_time(it, r); ++it) {
      if (compact) {
        build_compact(clamp);
      } else {
        build_jacobian(clamp, ori_scale);
        drop_saturated_columns();
        gram();
      }
      switch (meth) {
        case Method::jacobian_transpose: {
          // Buss 2004 eq. 7: alpha = <e, J J^T e> / <J J^T e, J J^T e>
          double num = 0, den = 0;
          for (int i = 0; i < m; ++i) {
            double sum = 0;
            for (int k = 0; k < m; ++k) sum += Amat[i * m + k] * e[k];
            t[i] = sum;
            num += e[i] * sum;
            den += sum * sum;
          }
          const double alpha = den > 0 ? num / den : 0.0;
          jt_times(e.data());
          for (int c = 0; c < ncols; ++c) dtheta[c] *= alpha;
          break;
        }
        case Method::pseudo_inverse: {
          // J^+ e = J^T (J J^T)^-1 e; a ridge of 1e-9 of the trace keeps the
          // factorisation defined at exact singularities
          double tr = 0;
          for (int i = 0; i < m; ++i) tr += Amat[i * m + i];
          const double ridge = 1e-9 * tr / m + 1e-300;
          if (!detail::cholesky_solve(Amat.data(), m, ridge, L.data(), e.data(), y.data()))
            std::fill(y.begin(), y.begin() + m, 0.0);
          jt_times(y.data());
          break;
        }
        case Method::dls: {
          // J^T (J J^T + lambda^2 I)^-1 e (Buss 2004 eq. 11)
          if (!detail::cholesky_solve(Amat.data(), m, lambda * lambda, L.data(), e.data(), y.data()))
            std::fill(y.begin(), y.begin() + m, 0.0);
          jt_times(y.data());
          break;
        }
        case Method::sdls:
          sdls_step(gamma);
          break;
        default:
          break;
      }
      clamp_max_abs(dtheta.data(), ncols, meth == Method::sdls ? gamma : step_cap);
      apply_dtheta(monotone);
      s.forward_kinematics();
      r.iterations = it + 1;
      if (monotone) {
        const double c = cost(ori_scale);
        if (c > prev_cost) {
          // reject: undo, damp more, and stop once the damping has grown a millionfold
          restore_pose();
          s.forward_kinematics();
          lambda *= 4;
          gamma *= 0.25;
          if (lambda > 1e6 * lambda0 || gamma < 1e-6 * step_cap || creep(r.iterations, r.residual)) break;
          continue;
        }
        prev_cost = c;
        lambda = std::max(0.5 * lambda, lambda0);
        gamma = std::min(2 * gamma, step_cap);
      }
      measure(r);
      if (!r.converged && (stalled(prev, r.residual) || creep(r.iterations, r.residual))) break;
      prev = r.residual;
    }
    measure(r);
  }

  // weighted sum of squared errors (orientation errors scaled to metres)
  double cost(double ori_scale) const {
    const Skeleton& s = *sk;
    double c = 0;
    for (int k = 0; k < ne; ++k) {
      const EffectorDef& ef = s.effector(k);
      const Vec3 d = s.tips()[ef.bone] - ef.target;
      c += ef.weight * ef.weight * glm::dot(d, d);
      if (ef.orientation) {
        const Vec3 o = detail::quat_log(*ef.orientation * glm::conjugate(s.world_rotations()[ef.bone]));
        c += ef.weight * ef.weight * ori_scale * ori_scale * glm::dot(o, o);
      }
    }
    return c;
  }

  // undo the last apply_dtheta(true): only the joints it changed
  void restore_pose() {
    Skeleton& s = *sk;
    for (int j : active_rev)
      if (col_of[j] >= 0) A::q(s)[j] = saved_q[j], A::angle(s)[j] = saved_angle[j];
    A::root_position(s) = saved_root;
  }

  // -------------------------------------------------------------------------
  // FABRIK (Aristidou and Lasenby 2011, "FABRIK: a fast, iterative solver for the
  // inverse kinematics problem", Graphical Models 73(5)). Stage 1 (forward reaching)
  // runs from the effectors to the root: each bone's tip goes to its target (or to the
  // centroid of the sub-base positions proposed by its children, Aristidou sec. 5) and
  // its start is pulled along the bone. Stage 2 (backward reaching) runs from the root:
  // each joint turns its bone toward the stage-1 tip goal, in joint coordinates, so the
  // joint type and limits are enforced exactly; this pass is also forward kinematics.
  void fabrik(SolveResult& r) {
    Skeleton& s = *sk;
    const int cap = max_iterations();
    const auto parents = s.parents();
    const auto types = s.joint_types();
    const auto lengths = s.lengths();
    const auto& limited = A::limited(s);
    const auto& lo = A::lo(s);
    const auto& hi = A::hi(s);
    const auto& swing = A::swing(s);
    const auto& axis = A::axis(s);
    auto& q = A::q(s);
    auto& ang = A::angle(s);
    auto& world = A::world(s);
    auto& start = A::start(s);
    auto& tip = A::tip(s);
    Vec3& root = A::root_position(s);
    const Quat root_rot = s.root_rotation();
    // unlimited ball joints without orientation targets constrain nothing but the bone
    // lengths: iterate on positions only and recover the rotations once at the end
    bool positions_only = all_free_balls;
    for (int k = 0; k < ne; ++k)
      if (s.effector(k).orientation) positions_only = false;
    double prev = r.residual, checkpoint = r.residual;
    bool handover = false;
    // one effector on free ball joints: the dedicated chain loop does all the iterations
    const bool chain_fast = positions_only && ne == 1;
    if (chain_fast) fabrik_chain(r);
    for (int it = 0; it < cap && !r.converged && !chain_fast && !out_of_time(it, r); ++it) {
      // stage 1: forward reaching, effectors to root
      Vec3 root_goal = root;
      for (int j : active_rev) {
        Vec3 g = acc[j];
        double ws = accw[j];
        const Quat* orient = nullptr;
        for (int u = eff_off[j]; u < eff_off[j + 1]; ++u) {
          const EffectorDef& ef = s.effector(eff_list[u]);
          g += ef.weight * ef.target;
          ws += ef.weight;
          if (ef.orientation && !orient) orient = &*ef.orientation;
        }
        g /= ws;
        acc[j] = Vec3(0);
        accw[j] = 0;
        goal[j] = g;
        // the bone's start, pulled toward the goal along the bone (or set by an orientation target)
        Vec3 sp;
        if (orient) {
          sp = g - detail::rotate_x(*orient, lengths[j]);
        } else if (types[j] == JointType::fixed) {
          // a welded bone keeps its current direction: translate it, do not turn it
          sp = g - (tip[j] - start[j]);
        } else {
          Vec3 d = start[j] - g;
          if (types[j] == JointType::hinge || (types[j] == JointType::ball && limited[j])) {
            // constrain the bone direction in the joint's current frame: a hinge keeps the
            // bone in its plane (and its angle range), a limited ball inside its cone.
            // Aristidou and Lasenby 2011 sec. 4 apply constraints in both stages too.
            const int p = parents[j];
            const Quat F = (p >= 0 ? world[p] : root_rot) * A::rest(s)[j];
            const Vec3 dl = detail::rotate_inv(F, -d);
            const double l2 = glm::dot(dl, dl);
            Vec3 c = dl;
            if (types[j] == JointType::hinge) {
              const double x = glm::dot(hx[j], dl), yv = glm::dot(hy[j], dl);
              if (x * x + yv * yv > 1e-12 * l2) {
                if (limited[j]) {
                  const double a = std::clamp(std::atan2(yv, x), lo[j], hi[j]);
                  c = std::cos(a) * hx[j] + std::sin(a) * hy[j];
                } else {
                  c = x * hx[j] + yv * hy[j];
                }
              }
            } else if (l2 > 1e-300) {
              const Vec3 u = dl / std::sqrt(l2);
              const double cl = std::cos(swing[j]);
              if (u.x < cl) {
                const double rl = std::sqrt(u.y * u.y + u.z * u.z);
                const double sl = std::sin(swing[j]);
                c = rl > 1e-15 ? Vec3(cl, sl * u.y / rl, sl * u.z / rl) : Vec3(cl, sl, 0);
              }
            }
            d = -detail::rotate(F, c);
          }
          const double l2 = glm::dot(d, d);
          sp = l2 > 1e-300 ? g + d * (lengths[j] / std::sqrt(l2)) : g - detail::rotate_x(world[j], lengths[j]);
        }
        const int p = parents[j];
        if (p >= 0) {
          acc[p] += sp;
          accw[p] += 1;
        } else {
          root_goal = sp;
        }
      }
      if (s.root_free()) root = root_goal;

      if (positions_only) {
        // stage 2 on positions: each tip at bone length from its start, toward its goal
        for (int i : active_fwd) {
          const int p = parents[i];
          const Vec3 st = p >= 0 ? tip[p] : root;
          const Vec3 d = goal[i] - st;
          const double l2 = glm::dot(d, d);
          const Vec3 old_dir = tip[i] - start[i];
          start[i] = st;
          tip[i] = l2 > 1e-300 ? st + d * (lengths[i] / std::sqrt(l2)) : st + old_dir;
        }
        r.iterations = it + 1;
        measure_tips(r);
        if (!r.converged && stalled(prev, r.residual)) break;
        prev = r.residual;
        continue;
      }

      // stage 2: backward reaching, root to effectors, in joint coordinates
      for (int i = 0; i < n; ++i) {
        const int p = parents[i];
        const Vec3 st = p >= 0 ? tip[p] : root;
        const Quat base = p >= 0 ? world[p] : root_rot;
        const Quat F = rest_identity[i] ? base : detail::qmul(base, A::rest(s)[i]);
        if (active[i]) {
          const JointType jt = types[i];
          if (jt == JointType::hinge) {
            // angle of the goal direction in the hinge plane
            const Vec3 dl = detail::rotate_inv(F, goal[i] - st);
            const double x = glm::dot(hx[i], dl), yv = glm::dot(hy[i], dl);
            if (x * x + yv * yv > 1e-300) {
              double a = std::atan2(yv, x);
              if (limited[i]) a = std::clamp(a, lo[i], hi[i]);
              ang[i] = a;
              const double sh = std::sin(0.5 * a);
              q[i] = Quat(std::cos(0.5 * a), axis[i].x * sh, axis[i].y * sh, axis[i].z * sh);
            }
          } else if (jt == JointType::ball) {
            const Quat* orient = nullptr;
            for (int u = eff_off[i]; u < eff_off[i + 1]; ++u)
              if (s.effector(eff_list[u]).orientation) {
                orient = &*s.effector(eff_list[u]).orientation;
                break;
              }
            if (orient) {
              // an orientation target sets the whole joint rotation
              q[i] = glm::conjugate(F) * *orient;
              if (limited[i]) q[i] = detail::clamp_ball(q[i], swing[i], lo[i], hi[i]);
            } else {
              Vec3 d = detail::rotate_inv(F, goal[i] - st);
              const double l2 = glm::dot(d, d);
              if (l2 > 1e-300) {
                d /= std::sqrt(l2);
                // keep the swing inside the cone
                if (limited[i] && swing[i] < kPi) {
                  const double cl = std::cos(swing[i]);
                  if (d.x < cl) {
                    const double rl = std::sqrt(d.y * d.y + d.z * d.z);
                    const double sl = std::sin(swing[i]);
                    d = rl > 1e-15 ? Vec3(cl, sl * d.y / rl, sl * d.z / rl) : Vec3(cl, sl, 0);
                  }
                }
                // shortest arc from +X to d, then the joint's previous twist
                Quat sw;
                if (d.x > -1 + 1e-12) {
                  sw = Quat(1 + d.x, 0, -d.z, d.y);
                  sw = sw * (1 / std::sqrt(sw.w * sw.w + sw.y * sw.y + sw.z * sw.z));
                } else {
                  sw = Quat(0, 0, 1, 0);
                }
                const Quat& o = q[i];
                const double tn = std::sqrt(o.w * o.w + o.x * o.x);
                Quat tw = tn > 1e-12 ? Quat(o.w / tn, o.x / tn, 0, 0) : Quat(1, 0, 0, 0);
                if (hinge_child[i] >= 0) tw = twist_for_hinge_child(i, F, sw, st, tw);
                q[i] = detail::qmul(sw, tw);
              }
            }
          }
        }
        const Quat wi = detail::qmul(F, q[i]);
        detail::put(world[i], wi);
        start[i] = st;
        tip[i] = st + detail::rotate_x(wi, lengths[i]);
      }
      r.iterations = it + 1;
      measure(r);
      if (!r.converged && stalled(prev, r.residual)) break;
      prev = r.residual;
      // with joint constraints the passes can fight the limits and creep (or circle an
      // unreachable target) instead of converging: when 8 iterations have not halved the
      // error, damped least squares (monotone, limit-aware) takes the remaining iterations
      if (r.converged || (it + 1) % 8 != 0) continue;
      if (r.residual > 0.5 * checkpoint) {
        handover = true;
        break;
      }
      checkpoint = r.residual;
    }
    // (a simple chain's new positions are still in cp: fabrik_chain did not scatter them)
    if (positions_only) rebuild_rotations(chain_fast && simple_chain ? cp.data() : nullptr);
    if (handover && !r.out_of_time) jacobian(r, Method::dls);
  }

  // joint rotations from the bone directions positions-only FABRIK left in start/tip
  // (detail::rebuild_rotations), then the transforms of bones off every effector's path
  void rebuild_rotations(const Vec3* points) {
    Skeleton& s = *sk;
    detail::RebuildArgs args{active_fwd.data(),      static_cast<int>(active_fwd.size()),
                             s.parents().data(),     s.lengths().data(),
                             inv_len.data(),         rest_identity.data(),
                             A::rest(s).data(),      A::root_position(s),
                             s.root_rotation(),      A::world(s).data(),
                             A::q(s).data(),         A::start(s).data(),
                             A::tip(s).data(),       scratch.data(),
                             simple_chain,           points};
    detail::rebuild_rotations(args);
    // bones off every effector's path still need their transforms
    if (static_cast<int>(active_fwd.size()) != s.bone_count()) s.forward_kinematics();
  }

  // The twist of ball joint i that turns its hinge child's plane onto the child's goal
  // (a ball joint's twist is otherwise never solved by positions alone, and a knee or
  // elbow could then never leave its plane). With a' the child's hinge axis in bone i's
  // frame and v the vector from bone i's tip to the child's goal, in that frame before
  // twist, twisting by tau about +X makes (R_x(tau) a') . v = A cos tau + B sin tau + C
  // vanish; of the two roots, keep the one whose child hinge angle fits the child's limits
  // (then the one nearer the current twist), clamped to bone i's twist range.
  Quat twist_for_hinge_child(int i, const Quat& F, const Quat& sw, const Vec3& st, const Quat& tw_old) {
    Skeleton& s = *sk;
    const int c = hinge_child[i];
    const Quat Fs = detail::qmul(F, sw);
    const Vec3 tip_i = st + detail::rotate_x(Fs, s.lengths()[i]);
    const Vec3 v = detail::rotate_inv(Fs, goal[c] - tip_i);
    const Vec3 a = detail::rotate(A::rest(s)[c], A::axis(s)[c]);
    const double Ac = a.y * v.y + a.z * v.z, Bc = a.y * v.z - a.z * v.y, Cc = a.x * v.x;
    const double R = std::sqrt(Ac * Ac + Bc * Bc);
    if (R < 1e-12 * (glm::length(v) + 1e-300)) return tw_old;
    const double phi = std::atan2(Bc, Ac), delta = std::acos(std::clamp(-Cc / R, -1.0, 1.0));
    const double old = 2 * std::atan2(tw_old.x, tw_old.w);
    const bool limited = A::limited(s)[i] != 0;
    double best = old, best_score = 1e300;
    for (double cand : {phi + delta, phi - delta}) {
      double t = detail::wrap_angle(cand);
      if (limited) t = std::clamp(t, A::lo(s)[i], A::hi(s)[i]);
      // the child's hinge angle toward its goal with this twist
      const Quat tq(std::cos(0.5 * t), std::sin(0.5 * t), 0, 0);
      const Vec3 dl = detail::rotate_inv(detail::qmul(tq, A::rest(s)[c]), v);
      const double th = std::atan2(glm::dot(hy[c], dl), glm::dot(hx[c], dl));
      const double out = A::limited(s)[c] ? std::max({0.0, A::lo(s)[c] - th, th - A::hi(s)[c]}) : 0.0;
      const double score = out + 1e-3 * std::abs(detail::wrap_angle(t - old));
      if (score < best_score) best_score = score, best = t;
    }
    return Quat(std::cos(0.5 * best), std::sin(0.5 * best), 0, 0);
  }

  // FABRIK on one chain of unlimited ball joints (the root-to-effector path), on
  // contiguous joint positions: stage 1 is a reaching pass from the target over the
  // joints in reverse, stage 2 one from the root over stage 1's points in reverse, both
  // by reach_pass (whose dependent path per joint is a square root, a multiplication
  // and a subtraction). Rotations are rebuilt once, after the last iteration.
  void fabrik_chain(SolveResult& r) {
    Skeleton& s = *sk;
    const int L = static_cast<int>(active_fwd.size());
    const int cap = max_iterations();
    auto& start = A::start(s);
    auto& tip = A::tip(s);
    // gather the path: cp[0] the root joint, cp[k + 1] the tip of path bone k (cl and clr,
    // its lengths forward and reversed, are set in prepare())
    cp[0] = start[active_fwd[0]];
    for (int k = 0; k < L; ++k) cp[k + 1] = tip[active_fwd[k]];
    const Vec3 target = s.effector(0).target;
    const bool free_root = s.root_free();
    const double tol = set.tolerance;
    double prev = r.residual;
    for (int it = 0; it < cap && !r.converged && !out_of_time(it, r); ++it) {
      // stage 1: from the target back to the root; fw[j] is the new tip of bone L-1-j
      const Vec3 root_goal = detail::reach_pass(target, &cp[L - 1], clr.data(), fw.data(), L);
      if (free_root) cp[0] = root_goal;
      // stage 2: from the root out to the effector, toward stage 1's tips
      const Vec3 end = detail::reach_pass(cp[0], &fw[L - 1], cl.data(), cp.data(), L);
      r.iterations = it + 1;
      r.residual = glm::length(end - target);
      r.converged = r.residual <= tol;
      if (!r.converged && stalled(prev, r.residual)) break;
      prev = r.residual;
    }
    // scatter back to the skeleton's arrays (a simple chain's rebuild reads cp itself)
    if (free_root) A::root_position(s) = cp[0];
    if (simple_chain) return;
    for (int k = 0; k < L; ++k) {
      start[active_fwd[k]] = cp[k];
      tip[active_fwd[k]] = cp[k + 1];
    }
  }

  // An unreachable target for one effector on a path of unlimited ball joints from a fixed
  // root: the closest reachable point is the tip of the straight path pointing at the target
  // (Aristidou and Lasenby 2011, Algorithm 1, tests this first), which the iterative methods
  // only approach slowly (DLS, SDLS and CCD need more than their caps at 1000 bones). Every
  // bone on the path turns, by its shortest arc, onto the root-target direction; returns
  // true when it did (the result is then final: no iteration improves on it).
  bool straighten_if_unreachable(SolveResult& r) {
    Skeleton& s = *sk;
    if (ne != 1 || !all_free_balls || s.root_free() || s.effector(0).orientation) return false;
    const int L = static_cast<int>(active_fwd.size());
    auto& start = A::start(s);
    auto& tip = A::tip(s);
    const Vec3 root = start[active_fwd[0]];
    const Vec3 d = s.effector(0).target - root;
    const double d2 = glm::dot(d, d);
    if (!(d2 > path_reach * path_reach)) return false;
    // the straight path, then the rotations and forward kinematics from it
    const Vec3 u = d / std::sqrt(d2);
    Vec3 p = root;
    for (int k = 0; k < L; ++k) {
      const int i = active_fwd[k];
      start[i] = p;
      p += u * cl[k];
      tip[i] = p;
    }
    rebuild_rotations(nullptr);
    r.iterations = 1;
    measure(r);
    return true;
  }

  // residual from the tips only (positions-only FABRIK keeps world rotations stale)
  void measure_tips(SolveResult& r) const {
    const Skeleton& s = *sk;
    r.residual = 0;
    for (int k = 0; k < ne; ++k) {
      const EffectorDef& ef = s.effector(k);
      r.residual = std::max(r.residual, glm::length(s.tips()[ef.bone] - ef.target));
    }
    r.converged = r.residual <= set.tolerance;
  }

  SolveResult solve() {
    Skeleton& s = *sk;
    prepare();
    // whether the method applies depends only on the effectors and the method: checked once
    if (supported_version != prepared_version || supported_method != set.method) {
      std::string why;
      if (!supports(set.method, s, &why)) throw Error("ik::Solver: " + why);
      supported_version = prepared_version;
      supported_method = set.method;
    }
    has_deadline = set.max_seconds > 0;
    if (has_deadline)
      deadline = std::chrono::steady_clock::now() +
                 std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                     std::chrono::duration<double>(std::min(set.max_seconds, 1e9)));
    if (!set.warm_start) s.reset_pose();
    // every solver leaves kinematics current, so a warm start usually skips this pass
    if (s.kinematics_dirty()) s.forward_kinematics();
    SolveResult r;
    measure(r);
    if (ne == 0 || r.converged) return r;
    if (set.method == Method::ccd || set.method == Method::fabrik || set.method == Method::dls ||
        set.method == Method::sdls || set.method == Method::pseudo_inverse ||
        set.method == Method::jacobian_transpose)
      if (straighten_if_unreachable(r)) return r;
    switch (set.method) {
      case Method::analytic_1dof: analytic_1dof(r); break;
      case Method::analytic_3dof: analytic_3dof(r); break;
      case Method::two_bone: {
        const SolveResult t2 = detail::solve_two_bone(s, set);
        r.iterations = t2.iterations;
        break;
      }
      case Method::ccd: ccd(r); break;
      case Method::jacobian_transpose:
      case Method::pseudo_inverse:
      case Method::dls:
      case Method::sdls: jacobian(r, set.method); break;
      case Method::fabrik: fabrik(r); break;
    }
    measure(r);
    return r;
  }
};

Solver::Solver(Skeleton& skeleton, const SolverSettings& settings) {
  settings.validate();
  impl_ = std::make_unique<Impl>(skeleton, settings);
}
Solver::Solver(Skeleton& skeleton, Method m) {
  SolverSettings st;
  st.method = m;
  impl_ = std::make_unique<Impl>(skeleton, st);
}
Solver::~Solver() = default;
Solver::Solver(Solver&&) noexcept = default;
Solver& Solver::operator=(Solver&&) noexcept = default;

void Solver::set_settings(const SolverSettings& settings) {
  settings.validate();
  impl_->set = settings;
}
const SolverSettings& Solver::settings() const { return impl_->set; }
void Solver::set_method(Method m) {
  SolverSettings s = impl_->set;
  s.method = m;
  set_settings(s);
}
SolveResult Solver::solve() { return impl_->solve(); }

// ---------------------------------------------------------------------------
// solve, then blend toward the solution (workbook 2.7 exercise 3)

SolveThenBlend::SolveThenBlend(Skeleton& visible, const SolverSettings& settings, Blend blend,
                               double blend_rate, int max_attempts)
    : visible_(&visible), work_(visible), solver_(work_, settings), blend_(blend),
      rate_(blend_rate), max_attempts_(max_attempts) {
  require_positive(blend_rate, "SolveThenBlend blend_rate");
  require_count(max_attempts, 1, 1000000, "SolveThenBlend max_attempts");
  goal_q_.assign(visible.bone_count(), Quat(1, 0, 0, 0));
  goal_angle_.assign(visible.bone_count(), 0.0);
}

SolveResult SolveThenBlend::update(double dt) {
  require_non_negative(dt, "SolveThenBlend::update dt");
  Skeleton& vis = *visible_;
  // copy the targets, solve on the private skeleton (continuing from its last pose)
  for (int k = 0; k < vis.effector_count() && k < work_.effector_count(); ++k) {
    work_.set_target(k, vis.effector(k).target);
    work_.set_orientation_target(k, vis.effector(k).orientation);
    work_.set_pole(k, vis.effector(k).pole);
  }
  SolveResult r;
  for (int attempt = 0; attempt < max_attempts_; ++attempt) {
    r = solver_.solve();
    if (r.converged) break;
  }
  // a converged pose becomes the new goal; otherwise the old goal stays
  if (r.converged) {
    const auto q = work_.joint_rotations();
    std::copy(q.begin(), q.end(), goal_q_.begin());
    const auto a = work_.hinge_angles();
    std::copy(a.begin(), a.end(), goal_angle_.begin());
    goal_root_ = work_.root_position();
    blending_ = true;
  }
  if (!blending_) return r;
  // move a fraction 1 - exp(-rate dt) of the way toward the goal, per joint
  const double f = 1 - std::exp(-rate_ * dt);
  if (f <= 0) return r;
  auto& q = A::q(vis);
  auto& angle = A::angle(vis);
  double remaining = 0;
  for (int i = 0; i < vis.bone_count(); ++i) {
    Quat g = goal_q_[i];
    if (glm::dot(g, q[i]) < 0) g = -g;
    if (vis.joint_types()[i] == JointType::hinge) {
      const double target = goal_angle_[i];
      angle[i] += f * (target - angle[i]);
      remaining = std::max(remaining, std::abs(target - angle[i]));
    } else {
      q[i] = blend_ == Blend::slerp ? glm::slerp(q[i], g, f) : glm::normalize(glm::lerp(q[i], g, f));
      remaining = std::max(remaining, 2 * std::acos(std::min(1.0, std::abs(glm::dot(q[i], g)))));
    }
    A::clamp_joint(vis, i);
  }
  A::root_position(vis) += f * (goal_root_ - vis.root_position());
  vis.forward_kinematics();
  if (remaining < 1e-6) blending_ = false;
  return r;
}

}  // namespace pba::ik
