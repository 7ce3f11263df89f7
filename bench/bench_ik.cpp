// IK benchmark: every pba solver on chains of 10, 100 and 1000 bones (total length
// 1 m), with and without joint limits, against orocos KDL (ChainIkSolverPos_LMA and
// ChainIkSolverPos_NR_JL) on the same chains and targets at the same tolerance.
//
//   bench_ik [--quick] [--targets N] [--budget SECONDS]
//
// Prints markdown tables: cold solves to random reachable targets (made from random
// joint angles, fixed seed), unreachable targets, and 600 frames tracking a moving
// target with warm start. Timings are wall-clock per solve on one thread; quote
// medians and ratios (the machine may be shared).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <new>
#include <random>
#include <string>
#include <vector>

#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainiksolverpos_lma.hpp>
#include <kdl/chainiksolverpos_nr_jl.hpp>
#include <kdl/chainiksolvervel_pinv.hpp>

#include "pba/ik.h"
#include "pba/ik_scenes.h"
#include "alloc_count.h"

// count heap allocations (alloc_count.cpp replaces the global operator new)
namespace {
using pba::test_support::g_allocations;
}

namespace {

using namespace pba;
using namespace pba::ik;
using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// per-solve times are this thread's CPU time, so pre-emption by other processes on a
// shared machine does not count; the cost of reading the clock is measured and removed
double cpu_now() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}
double g_clock_cost = 0;
double cpu_elapsed(double t0, double t1) { return std::max(0.0, t1 - t0 - g_clock_cost); }
void calibrate_clock() {
  std::vector<double> d;
  for (int i = 0; i < 2001; ++i) {
    const double a = cpu_now(), b = cpu_now();
    d.push_back(b - a);
  }
  std::sort(d.begin(), d.end());
  g_clock_cost = d[d.size() / 2];
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t i = std::min(v.size() - 1, static_cast<std::size_t>(q * (v.size() - 1) + 0.5));
  return v[i];
}

struct Row {
  Row(std::string b, std::string l, std::string s)
      : bones(std::move(b)), limits(std::move(l)), solver(std::move(s)) {}
  std::string bones, limits, solver;
  int solves = 0, success = 0;
  std::vector<double> iters, t_solve, t_iter, err;
  double allocs = 0;
  std::string note;

  // one timed solve: thread CPU clock readings t0, t1 around it, its iteration count (< 0
  // when the solver does not expose it: 0 iterations and 0 per iteration are reported),
  // whether it succeeded and its error (m)
  void add(double t0, double t1, int iterations, bool ok, double error) {
    solves++;
    success += ok;
    iters.push_back(std::max(0, iterations));
    t_solve.push_back(cpu_elapsed(t0, t1));
    t_iter.push_back(iterations < 0 ? 0.0 : cpu_elapsed(t0, t1) / std::max(1, iterations));
    err.push_back(error);
  }
};

void print_header(const char* title) {
  std::printf("\n### %s\n\n", title);
  std::printf("| bones | limits | solver | solves | success | iters (med) | solve med (us) | solve p99 (us) "
              "| iter med (us) | iter p99 (us) | error med (m) | error max (m) | allocs/solve |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
}

void print_row(const Row& r) {
  std::printf("| %s | %s | %s | %d | %.1f%% | %.0f | %.1f | %.1f | %.3f | %.3f | %.1e | %.1e | %.1f |%s\n",
              r.bones.c_str(), r.limits.c_str(), r.solver.c_str(), r.solves,
              r.solves ? 100.0 * r.success / r.solves : 0.0, quantile(r.iters, 0.5),
              1e6 * quantile(r.t_solve, 0.5), 1e6 * quantile(r.t_solve, 0.99),
              1e6 * quantile(r.t_iter, 0.5), 1e6 * quantile(r.t_iter, 0.99), quantile(r.err, 0.5),
              quantile(r.err, 1.0), r.allocs, r.note.empty() ? "" : (" " + r.note).c_str());
  std::fflush(stdout);
}

// --- pba ---

// the chains: ball joints (scenes::make_chain), hinges, or hinges and ball joints mixed
enum class Joints { Ball, Hinge, Mixed };
Skeleton make_chain(int n, bool limited, Joints j) {
  if (j == Joints::Mixed) return scenes::make_mixed_chain(n, limited);
  return scenes::make_chain(n, j == Joints::Hinge ? JointType::Hinge : JointType::Ball, limited);
}

Row run_pba_cold(int n, bool limited, Method m, const std::vector<scenes::Target>& targets, double tol,
                 double budget, bool orientation, Joints joints = Joints::Ball) {
  Skeleton s = make_chain(n, limited, joints);
  EffectorDef ef;
  ef.bone = n - 1;
  s.add_effector(ef);
  SolverSettings st;
  st.method = m;
  st.tolerance = tol;
  Solver solver(s, st);
  const char* kind = joints == Joints::Hinge ? " hinges" : joints == Joints::Mixed ? " mixed" : "";
  Row r{std::to_string(n), limited ? "yes" : "no", std::string(name(m)) + (orientation ? " 6D" : "") + kind};
  long long allocs = 0;
  int handed = 0;
  const auto t_begin = Clock::now();
  for (const auto& t : targets) {
    scenes::bent_pose(s);
    s.set_target(0, t.position);
    s.set_orientation_target(0, orientation ? std::optional<Quat>(t.rotation) : std::nullopt);
    const long long a0 = g_allocations.load();
    const double t0 = cpu_now();
    const SolveResult res = solver.solve();
    const double t1 = cpu_now();
    allocs += g_allocations.load() - a0;
    r.add(t0, t1, res.iterations, res.converged, res.residual);
    handed += res.handed_over;
    if (!s.within_limits(1e-9)) r.note = "LIMITS VIOLATED";
    if (seconds(t_begin, Clock::now()) > budget) break;
  }
  r.allocs = r.solves ? double(allocs) / r.solves : 0;
  if (handed && r.note.empty()) r.note = "(" + std::to_string(handed) + " handed over to DLS)";
  return r;
}

// unreachable: targets at 1.5 m (chain length 1 m) in random directions; the error
// reported is the excess over the closest reachable distance, 0.5 m
Row run_pba_unreachable(int n, Method m, double tol, int count) {
  Skeleton s = scenes::make_chain(n, JointType::Ball, false);
  EffectorDef ef;
  ef.bone = n - 1;
  s.add_effector(ef);
  SolverSettings st;
  st.method = m;
  st.tolerance = tol;
  Solver solver(s, st);
  Row r{std::to_string(n), "no", std::string(name(m)) + " unreachable"};
  std::mt19937_64 rng(99);
  std::normal_distribution<double> g;
  long long allocs = 0;
  for (int k = 0; k < count; ++k) {
    Vec3 d(g(rng), g(rng), g(rng));
    d = glm::normalize(d);
    scenes::bent_pose(s);
    s.set_target(0, 1.5 * d);
    const long long a0 = g_allocations.load();
    const double t0 = cpu_now();
    const SolveResult res = solver.solve();
    const double t1 = cpu_now();
    allocs += g_allocations.load() - a0;
    const double excess = std::abs(res.residual - 0.5);
    r.add(t0, t1, res.iterations, excess <= 1e-3, excess);
  }
  r.allocs = double(allocs) / count;
  r.note = "(success: within 1e-3 m of the closest reachable distance)";
  return r;
}

// tracking: a target that moves smoothly through reachable space (the tip of a pose
// whose joint angles vary sinusoidally), 600 frames at 60 Hz, warm start
Row run_pba_tracking(int n, bool limited, Method m, double tol) {
  Skeleton s = scenes::make_chain(n, JointType::Ball, limited);
  Skeleton driver = scenes::make_chain(n, JointType::Ball, limited);
  EffectorDef ef;
  ef.bone = n - 1;
  s.add_effector(ef);
  SolverSettings st;
  st.method = m;
  st.tolerance = tol;
  Solver solver(s, st);
  Row r{std::to_string(n), limited ? "yes" : "no", std::string(name(m)) + " tracking"};
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 6.283185307179586);
  std::vector<double> phase(n);
  for (double& p : phase) p = u(rng);
  long long allocs = 0;
  const double amp = limited ? 0.4 : 0.8;
  auto drive = [&](double time) {
    for (int i = 0; i < n; ++i) {
      const double sw = amp * std::sin(0.7 * time + phase[i]);
      driver.set_joint_rotation(i, glm::angleAxis(sw, Vec3(0, std::cos(phase[i]), std::sin(phase[i]))));
    }
    driver.forward_kinematics();
  };
  // tracking starts on the target: the chain takes the driver's pose at t = 0
  drive(0);
  for (int i = 0; i < n; ++i) s.set_joint_rotation(i, driver.joint_rotations()[i]);
  for (int f = 1; f <= 600; ++f) {
    drive(f / 60.0);
    s.set_target(0, driver.tips()[n - 1]);
    const long long a0 = g_allocations.load();
    const double t0 = cpu_now();
    const SolveResult res = solver.solve();
    const double t1 = cpu_now();
    allocs += g_allocations.load() - a0;
    r.add(t0, t1, res.iterations, res.converged, res.residual);
  }
  r.allocs = double(allocs) / 600;
  return r;
}

// --- KDL: a ball joint is three revolute joints Z, Y, X (the X one carries the bone) ---

KDL::Chain kdl_chain(int n) {
  KDL::Chain c;
  const double len = 1.0 / n;
  for (int i = 0; i < n; ++i) {
    c.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::RotZ), KDL::Frame::Identity()));
    c.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::RotY), KDL::Frame::Identity()));
    c.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::RotX), KDL::Frame(KDL::Vector(len, 0, 0))));
  }
  return c;
}

KDL::JntArray kdl_bent(int n) {
  KDL::JntArray q(3 * n);
  const double a = std::min(0.3, 3.0 / n);
  for (int i = 0; i < n; ++i) q(3 * i) = a;
  return q;
}

KDL::Frame kdl_frame(const scenes::Target& t) {
  const KDL::Rotation R = KDL::Rotation::Quaternion(t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w);
  return KDL::Frame(R, KDL::Vector(t.position.x, t.position.y, t.position.z));
}

// cold solves of a KDL position solver from the same bent pose to each target, timed like
// pba's rows; the error is measured by a separate forward-kinematics pass. `six_d` also
// asks the end rotation within 1e-3 rad (for solvers that stop only on the full 6D twist
// error); solvers that do not expose their iteration count report 0 iterations
template <class Ik>
Row run_kdl(Ik& ik, const KDL::Chain& chain, int n, const char* name, const std::vector<scenes::Target>& targets,
            double tol, double budget, bool six_d) {
  KDL::ChainFkSolverPos_recursive fk(chain);
  Row r{std::to_string(n), "no", name};
  KDL::JntArray q0 = kdl_bent(n), q(3 * n);
  long long allocs = 0;
  const auto t_begin = Clock::now();
  for (const auto& t : targets) {
    const KDL::Frame goal = kdl_frame(t);
    const long long a0 = g_allocations.load();
    const double t0 = cpu_now();
    ik.CartToJnt(q0, goal, q);
    const double t1 = cpu_now();
    allocs += g_allocations.load() - a0;
    KDL::Frame f;
    fk.JntToCart(q, f);
    const double err = (f.p - goal.p).Norm();
    int iterations = -1;
    if constexpr (requires { ik.lastNrOfIter; }) iterations = ik.lastNrOfIter;
    r.add(t0, t1, iterations, err <= tol && (!six_d || KDL::diff(f.M, goal.M).Norm() <= 1e-3), err);
    if (seconds(t_begin, Clock::now()) > budget) break;
  }
  r.allocs = r.solves ? double(allocs) / r.solves : 0;
  return r;
}

Row run_kdl_lma(int n, const std::vector<scenes::Target>& targets, double tol, double budget) {
  KDL::Chain chain = kdl_chain(n);
  Eigen::Matrix<double, 6, 1> L;
  L << 1, 1, 1, 0, 0, 0;  // position only
  KDL::ChainIkSolverPos_LMA ik(chain, L, tol, 500, 1e-15);
  return run_kdl(ik, chain, n, "KDL LMA", targets, tol, budget, false);
}

// NR_JL stops only on the full 6D twist error, so it gets 6D targets (position and the
// random pose's end rotation); compare with pba's rows marked "6D"
Row run_kdl_nrjl(int n, const std::vector<scenes::Target>& targets, double tol, double budget) {
  KDL::Chain chain = kdl_chain(n);
  KDL::JntArray qmin(3 * n), qmax(3 * n);
  for (int i = 0; i < 3 * n; ++i) qmin(i) = -2 * M_PI, qmax(i) = 2 * M_PI;
  KDL::ChainFkSolverPos_recursive fk(chain);
  KDL::ChainIkSolverVel_pinv vel(chain);
  KDL::ChainIkSolverPos_NR_JL ik(chain, qmin, qmax, fk, vel, 500, tol);
  Row r = run_kdl(ik, chain, n, "KDL NR_JL 6D", targets, tol, budget, true);
  r.note = "(iterations not exposed)";
  return r;
}

// two-bone analytic: a ball shoulder and a hinge elbow
Row run_two_bone(int count) {
  SkeletonDef def;
  def.bones.resize(2);
  def.bones[0].length = 0.3;
  def.bones[1].parent = 0;
  def.bones[1].length = 0.25;
  def.bones[1].joint = JointType::Hinge;
  Skeleton s(def);
  EffectorDef ef;
  ef.bone = 1;
  ef.pole = Vec3(0, 1, 0);
  s.add_effector(ef);
  SolverSettings st;
  st.method = Method::TwoBone;
  Solver solver(s, st);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-0.4, 0.4);
  Row r{"2", "no", "two_bone (Solver, batch of 100)"};
  long long allocs = 0;
  std::vector<Vec3> targets;
  while (static_cast<int>(targets.size()) < 100) {
    const Vec3 t(u(rng), u(rng), u(rng));
    if (glm::length(t) <= 0.54 && glm::length(t) >= 0.06) targets.push_back(t);
  }
  for (int batch = 0; batch < count / 100; ++batch) {
    const long long a0 = g_allocations.load();
    double worst = 0;
    bool all = true;
    const double t0 = cpu_now();
    for (const Vec3& t : targets) {
      s.set_target(0, t);
      const SolveResult res = solver.solve();
      worst = std::max(worst, res.residual);
      all = all && res.converged;
    }
    const double t1 = cpu_now();
    allocs += g_allocations.load() - a0;
    r.solves += 100;
    r.success += all ? 100 : 0;
    r.iters.push_back(1);
    r.t_solve.push_back(cpu_elapsed(t0, t1) / 100);
    r.t_iter.push_back(cpu_elapsed(t0, t1) / 100);
    r.err.push_back(worst);
  }
  r.allocs = double(allocs) / r.solves;
  // the bare job, timed in batches (one call is shorter than the clock's resolution)
  Row j{"2", "no", "TwoBoneJob::run (batch of 1000)"};
  TwoBoneJob job;
  job.start = Vec3(0);
  job.mid = Vec3(0.3, 0, 0);
  job.end = Vec3(0.3, 0.25, 0);
  job.pole = Vec3(0, 1, 0);
  for (int b = 0; b < 200; ++b) {
    const double t0 = cpu_now();
    double sink = 0;
    for (int k = 0; k < 1000; ++k) {
      job.target = Vec3(0.2 + 1e-4 * k, 0.1, 0.05);
      job.run();
      sink += job.start_correction.w;
    }
    const double t1 = cpu_now();
    j.solves += 1000;
    j.success += sink != 0 ? 1000 : 0;
    j.iters.push_back(1);
    j.t_solve.push_back(cpu_elapsed(t0, t1) / 1000);
    j.t_iter.push_back(cpu_elapsed(t0, t1) / 1000);
    j.err.push_back(0);
  }
  print_row(r);
  return j;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, kdl = true;
  int ntargets = 1000, only_n = 0;
  std::string only_method;
  double budget = 20;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick")) quick = true, ntargets = 100, budget = 3;
    else if (!std::strcmp(argv[i], "--targets") && i + 1 < argc) ntargets = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--budget") && i + 1 < argc) budget = std::atof(argv[++i]);
    else if (!std::strcmp(argv[i], "--n") && i + 1 < argc) only_n = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--method") && i + 1 < argc) only_method = argv[++i];
    else if (!std::strcmp(argv[i], "--no-kdl")) kdl = false;
    else {
      // an unknown flag (or --help) is not a request for the full 10-minute run
      std::fprintf(stderr,
                   "bench_ik: unknown argument '%s'\n"
                   "usage: bench_ik [--quick] [--targets N] [--budget SECONDS] [--n BONES] [--method NAME] [--no-kdl]\n",
                   argv[i]);
      return 2;
    }
  }
  const double tol = 1e-4;  // chains are 1 m long: 1e-4 of the chain length
  calibrate_clock();
  std::printf("# pba IK benchmark\n\nchains of ball joints, total length 1 m, tolerance %.0e m; "
              "%d random reachable targets (seed 1), cold solves from the same bent pose; "
              "each row stops after %.0f s of solving and reports the solves done. Times are thread CPU "
              "time (clock read cost %.0f ns removed).\n",
              tol, ntargets, budget, 1e9 * g_clock_cost);
  std::vector<Method> iterative = {Method::Fabrik, Method::Ccd, Method::Dls, Method::Sdls,
                                   Method::PseudoInverse, Method::JacobianTranspose};
  std::vector<int> sizes = {10, 100, 1000};
  if (only_n) sizes = {only_n};
  if (!only_method.empty()) iterative = {parse_method(only_method, "--method")};
  auto want = [&](Method m) {
    return std::find(iterative.begin(), iterative.end(), m) != iterative.end();
  };
  print_header("Cold solves, random reachable targets");
  for (int n : sizes) {
    for (bool limited : {false, true}) {
      Skeleton s = scenes::make_chain(n, JointType::Ball, limited);
      const auto targets = scenes::random_targets(s, n - 1, ntargets, 1);
      for (Method m : iterative) print_row(run_pba_cold(n, limited, m, targets, tol, budget, false));
      if (!limited && kdl) {
        print_row(run_kdl_lma(n, targets, tol, budget));
        print_row(run_pba_cold(n, false, Method::Dls, targets, tol, budget, true));
        print_row(run_pba_cold(n, false, Method::Fabrik, targets, tol, budget, true));
        print_row(run_kdl_nrjl(n, targets, tol, budget));
      }
    }
  }
  // long chains of other joints (issue 12: CCD reached 68% of a 333-bone chain's targets)
  print_header("Cold solves on 333-bone chains of limited hinges, and of mixed hinges and ball joints");
  for (Joints j : {Joints::Hinge, Joints::Mixed}) {
    if (only_n && only_n != 333) break;
    Skeleton s = make_chain(333, true, j);
    const auto targets = scenes::random_targets(s, 332, std::min(ntargets, 300), 1);
    for (Method m : {Method::Fabrik, Method::Ccd, Method::Dls})
      if (want(m)) print_row(run_pba_cold(333, true, m, targets, tol, budget, false, j));
  }
  print_header("Unreachable targets (1.5 m from the root of a 1 m chain)");
  for (int n : sizes)
    for (Method m : {Method::Fabrik, Method::Ccd, Method::Dls, Method::Sdls})
      if (want(m)) print_row(run_pba_unreachable(n, m, tol, quick ? 20 : 100));
  print_header("Tracking a moving target, 600 frames, warm start");
  for (int n : sizes)
    for (bool limited : {false, true})
      for (Method m : {Method::Fabrik, Method::Ccd, Method::Dls})
        if (want(m)) print_row(run_pba_tracking(n, limited, m, tol));
  print_header("Analytic two-bone");
  print_row(run_two_bone(quick ? 2000 : 20000));
  return 0;
}
