// The fused semi-implicit Euler particle step: forces, forcers, integration, collisions
// and the finite check in one pass over memory, block by block.
#include "kernels.h"

namespace pba::detail {

namespace {

// One block: accelerations into L1 scratch, kick then drift (keeping the old positions
// and velocities for the swept collision tests), collisions, finite check. The arithmetic
// is exactly Integrator::step_semi_implicit_euler's (v += a h; x += v h) with the same
// force code. Everything is passed as plain pointers and values so nothing can alias.
PBA_INLINE void fused_block(float* PBA_RESTRICT x, float* PBA_RESTRICT y, float* PBA_RESTRICT z,
                            float* PBA_RESTRICT vx, float* PBA_RESTRICT vy, float* PBA_RESTRICT vz,
                            const float* PBA_RESTRICT im, const float* PBA_RESTRICT radius, int n, float h,
                            const ForceParams forces, const ForcerParams* forcers, std::size_t n_forcers,
                            const ColliderParams* colliders, std::size_t n_colliders, float threshold,
                            FusedResult& out) {
  alignas(64) float ax[kBlock], ay[kBlock], az[kBlock], ox[kBlock], oy[kBlock], oz[kBlock];
  alignas(64) float ovx[kBlock], ovy[kBlock], ovz[kBlock];
  // gravity, drag and wind, then each forcer volume
  base_accel(n, vx, vy, vz, im, forces, ax, ay, az);
  for (std::size_t f = 0; f < n_forcers; ++f) forcer_accel(n, x, y, z, im, forcers[f], ax, ay, az);
  // keep the start of the step when there are surfaces (for the swept tests), kick and
  // drift, and check the new state in the same pass
  int bad = 0;
  if (n_colliders == 0) {
    for (int k = 0; k < n; ++k) {
      vx[k] += ax[k] * h;
      vy[k] += ay[k] * h;
      vz[k] += az[k] * h;
      x[k] += vx[k] * h;
      y[k] += vy[k] * h;
      z[k] += vz[k] * h;
      bad |= non_finite6(x[k], y[k], z[k], vx[k], vy[k], vz[k]);
    }
  } else {
    for (int k = 0; k < n; ++k) {
      ox[k] = x[k];
      oy[k] = y[k];
      oz[k] = z[k];
      ovx[k] = vx[k];
      ovy[k] = vy[k];
      ovz[k] = vz[k];
      vx[k] += ax[k] * h;
      vy[k] += ay[k] * h;
      vz[k] += az[k] * h;
      x[k] += vx[k] * h;
      y[k] += vy[k] * h;
      z[k] += vz[k] * h;
      bad |= non_finite6(x[k], y[k], z[k], vx[k], vy[k], vz[k]);
    }
    // swept collisions against every surface; each checks the particles it changed
    out.contacts += static_cast<std::size_t>(collide_block(n, ox, oy, oz, ovx, ovy, ovz, x, y, z, vx, vy, vz, radius,
                                                           colliders, n_colliders, threshold, h, bad));
  }
  if (bad) out.non_finite = true;
}

}  // namespace

// compiled for AVX2 and for the baseline; the loader picks one at start-up (GCC function
// multi-versioning). -ffp-contract=off keeps both free of fused multiply-adds, so both
// give the same bits. Not under the sanitizers: the ifunc resolver runs during
// relocation, before the sanitizer runtime is up, and crashes the program (TSan).
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && \
    !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
__attribute__((target_clones("avx2", "default")))
#endif
FusedResult fused_semi_implicit_euler(const FusedArgs& a) {
  FusedResult out;
  // whole blocks, then the tail
  for (std::size_t b = 0; b < a.n; b += kBlock) {
    const int n = static_cast<int>(a.n - b < static_cast<std::size_t>(kBlock) ? a.n - b : kBlock);
    fused_block(a.x + b, a.y + b, a.z + b, a.vx + b, a.vy + b, a.vz + b, a.inv_mass + b, a.radius + b, n, a.h,
                a.forces, a.forcers, a.n_forcers, a.colliders, a.n_colliders, a.threshold, out);
  }
  return out;
}

}  // namespace pba::detail
