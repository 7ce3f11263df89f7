// Rigid bodies: contact pairs and their manifolds, with warm-start matching; what a step does
// before the solver. Each step:
//   1. every awake body's shapes get their tight bounds (grown by the speculative distance
//      and the step's motion); a shape that left the fat box the tree holds for it gets a
//      new one, set where its leaf stands (a dynamic AABB tree, Catto 2019; Box2D v3 enlarges
//      its proxies in place too), the tree rebuilt when its quality wore down; sleeping and
//      unmoved static bodies cost nothing;
//   2. only the shapes with new fat boxes query the tree, for pairs new to the persistent,
//      sorted list of shape pairs whose fat boxes overlap;
//   3. sleeping islands that a moving body reaches are woken;
//   4. each pair whose tight bounds overlap gets its manifolds: carried over from an earlier
//      step while the two bodies' relative pose stays within the reuse thresholds (Jolt's
//      body pair cache: the points stay fixed to the bodies, the normal to one of them), else
//      made by the narrow phase (collide(), or collide_mesh() per touching triangle), and
//      each point takes last step's impulse from the point with the same feature id (or the
//      nearest one).
// The pair list is sorted by (body slots, shapes), and a mesh pair's manifolds come in the
// order of the mesh's tree, so the solver sees the same order in every run. The solver
// passes are in contact_solver.cpp; the islands in rigid_body.cpp.
#include "contacts.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define PBA_EMIT_AVX2 1
#else
#define PBA_EMIT_AVX2 0
#endif

#include "collide/narrow_internal.h"
#include "collide/shape_bounds.h"
#include "core/lanes.h"
#include "rows_avx2.h"

namespace pba::detail {

namespace {

// an orthonormal basis (t1, t2) perpendicular to the unit n, a continuous function of n
// away from n = -z (Duff et al. 2017, "Building an orthonormal basis, revisited")
void tangent_basis(const Vec3& n, Vec3& t1, Vec3& t2) {
  const double sign = std::copysign(1.0, n.z);
  const double a = -1.0 / (sign + n.z), b = n.x * n.y * a;
  t1 = Vec3(1 + sign * n.x * n.x * a, sign * b, -sign * n.x);
  t2 = Vec3(b, sign + n.y * n.y * a, -n.y);
}

double mix(MixRule r, double a, double b) {
  switch (r) {
    case MixRule::GeometricMean: return std::sqrt(a * b);
    case MixRule::Minimum: return std::min(a, b);
    case MixRule::Maximum: return std::max(a, b);
    case MixRule::Average: return 0.5 * (a + b);
    case MixRule::Product: return a * b;
  }
  return a;
}

// the radius that turns a rolling-resistance coefficient into a lever arm (m)
double rolling_radius(const ColliderShape& s) {
  switch (s.type) {
    case ShapeType::Sphere:
    case ShapeType::Capsule: return s.radius;
    default: return 0;
  }
}

// the box a fat box is made from: the tight one, stretched by `ahead` (m) along the motion
// (inlined: update_proxies calls it twice for every awake body; as a call it was 0.7 M
// instructions of the rain's landing step)
inline __attribute__((always_inline)) Aabb stretched(const Aabb& box, const Vec3& ahead) {
  return {box.lo + glm::min(ahead, Vec3(0)), box.hi + glm::max(ahead, Vec3(0))};
}

// the manifolds of a mesh pair whose normals are within 5 degrees (the cosine; Jolt's
// manifold reduction angle) are merged into one: a body on a gently curved stretch of a mesh
// gets one manifold of at most four points, not one per triangle under it
constexpr double kMergeCos = 0.99619469809174553;
// merged points closer than this (m) are one point
constexpr double kSamePoint = 1e-6;

// how many pairs ahead make_manifolds() and emit() fetch the pool entries they will read
constexpr std::size_t kPairsAhead = 4;
// how many bodies ahead update_proxies() fetches the shapes it will read
constexpr std::size_t kBodiesAhead = 8;
// new shapes in one step beyond which update_proxies() rebuilds the tree over all its leaves
// rather than keep the insertions (the first step of a scene)
constexpr std::size_t kCreatedBeforeRebuild = 16;

// asks for every cache line that the `Bytes` from `at` touch (a prefetch: no effect on the
// results); from the line `at` is in, so an object that starts mid-line gets its last line
// too. The count is known but for that last line, so the loop unrolls (a loop of unknown
// count was 4% of the 1240 pyramid's manifolds phase by instructions)
template <std::size_t Bytes>
void prefetch_lines(const void* at) {
  const auto start = reinterpret_cast<std::uintptr_t>(at);
  const std::uintptr_t first = start & ~std::uintptr_t{63};
  constexpr std::size_t kLines = (Bytes + 63) / 64;
  for (std::size_t k = 0; k < kLines; ++k) __builtin_prefetch(reinterpret_cast<const void*>(first + 64 * k));
  if (first + 64 * kLines < start + Bytes) __builtin_prefetch(reinterpret_cast<const void*>(first + 64 * kLines));
}

}  // namespace

// ---------------------------------------------------------------------------------------
// the pair set

namespace {
// a 64-bit mix (splitmix64's finaliser) so that neighbouring keys spread over the table
std::uint64_t spread(std::uint64_t k) {
  k ^= k >> 30, k *= 0xbf58476d1ce4e5b9ull;
  k ^= k >> 27, k *= 0x94d049bb133111ebull;
  return k ^ (k >> 31);
}
}  // namespace

bool PairSet::contains(std::uint64_t key) const {
  if (slots.empty()) return false;
  const std::size_t mask = slots.size() - 1;
  for (std::size_t i = spread(key) & mask;; i = (i + 1) & mask) {
    if (slots[i] == key) return true;
    if (slots[i] == 0) return false;
  }
}

void PairSet::prefetch(std::uint64_t key) const {
  if (!slots.empty()) __builtin_prefetch(&slots[spread(key) & (slots.size() - 1)]);
}

bool PairSet::insert(std::uint64_t key) {
  // at most half full: grow by doubling (and rehash)
  if (2 * (count + 1) > slots.size()) {
    std::vector<std::uint64_t> old(std::max<std::size_t>(64, 2 * slots.size()), 0);
    old.swap(slots);
    count = 0;
    for (const std::uint64_t k : old)
      if (k != 0) insert(k);
  }
  const std::size_t mask = slots.size() - 1;
  for (std::size_t i = spread(key) & mask;; i = (i + 1) & mask) {
    if (slots[i] == key) return false;
    if (slots[i] == 0) {
      slots[i] = key;
      ++count;
      return true;
    }
  }
}

void PairSet::erase(std::uint64_t key) {
  if (slots.empty()) return;
  const std::size_t mask = slots.size() - 1;
  std::size_t i = spread(key) & mask;
  while (slots[i] != key) {
    if (slots[i] == 0) return;
    i = (i + 1) & mask;
  }
  // shift the run after the hole back over it, each key no farther than its home allows
  for (std::size_t j = (i + 1) & mask; slots[j] != 0; j = (j + 1) & mask) {
    const std::size_t home = spread(slots[j]) & mask;
    // j's key may move to i when its home is not cyclically within (i, j]
    if (((j - home) & mask) >= ((j - i) & mask)) slots[i] = slots[j], i = j;
  }
  slots[i] = 0;
  --count;
}

void PairSet::clear() {
  std::fill(slots.begin(), slots.end(), 0);
  count = 0;
}

// ---------------------------------------------------------------------------------------
// pools

std::uint32_t RigidContacts::new_cache() {
  if (free_cache != kNoIndex) {
    const std::uint32_t k = free_cache;
    free_cache = caches[k].first;
    caches[k] = PairCache{};
    return k;
  }
  caches.emplace_back();
  // (the spare pool grows with it, so reorder_caches() does not allocate in a later step)
  if (caches_spare.capacity() < caches.capacity()) caches_spare.reserve(caches.capacity());
  return static_cast<std::uint32_t>(caches.size() - 1);
}

// Pairs are made as shapes meet and end as they part, so the pool's order drifts from the
// pairs' (on the terrain, where bodies land and roll, the loads of the pair caches that the
// plan makes in pair order went to memory one by one: 31-38% of make_manifolds' samples
// on a single compare, whatever was prefetched 8 pairs ahead). In pair order the plan reads
// the pool as one stream. Only the indices change: no result does.
void RigidContacts::reorder_caches() {
  caches_spare.clear();
  for (ShapePair& p : shape_pairs) {
    if (p.cache == kNoIndex) continue;
    caches_spare.push_back(caches[p.cache]);
    p.cache = static_cast<std::uint32_t>(caches_spare.size() - 1);
  }
  caches.swap(caches_spare);
  free_cache = kNoIndex;
}

void RigidContacts::make_shape_pose(const RigidBodySystem& s, std::uint32_t q, std::uint32_t i, std::uint32_t k) {
  shape_poses[q] = shape_frame(s.body_pose(i), s.shapes_[i][k].local), shape_pose_stamp[q] = stamp;
}

std::uint32_t RigidContacts::new_manifold() {
  if (free_manifold != kNoIndex) {
    const std::uint32_t k = free_manifold;
    free_manifold = manifolds[k].next;
    manifolds[k].next = kNoIndex;
    manifolds[k].last = kNoIndex;
    return k;
  }
  manifolds.emplace_back();
  return static_cast<std::uint32_t>(manifolds.size() - 1);
}

// The impulses of `record` from the entry of `pairs` that holds them into the record itself
// (the entry is then no longer its).
void RigidContacts::settle(std::uint32_t record) {
  CachedManifold& r = manifolds[record];
  if (r.last == kNoIndex) return;
  ContactPair& c = pairs[r.last];
  // (all four: the slots past the count are read by no one, and a loop of the count was a
  // call of memcpy)
  for (int k = 0; k < Manifold::kMaxPoints; ++k) r.normal_impulse[k] = c.normal_impulse[k];
  r.friction = c.friction_impulse();
  r.twist = c.twist_impulse;
  r.rolling = c.rolling_impulse;
  c.record = kNoIndex;
  r.last = kNoIndex;
}

void RigidContacts::settle_all() {
  for (const ContactPair& c : pairs)
    if (c.record != kNoIndex) settle(c.record);
}

void RigidContacts::free_manifolds(PairCache& c) {
  for (std::uint32_t m = c.first; m != kNoIndex;) {
    const std::uint32_t next = manifolds[m].next;
    if (manifolds[m].last != kNoIndex) pairs[manifolds[m].last].record = kNoIndex, manifolds[m].last = kNoIndex;
    manifolds[m].next = free_manifold;
    free_manifold = m;
    m = next;
  }
  c.first = kNoIndex;
}

void RigidContacts::free_pair(ShapePair& p) {
  pair_set.erase(pair_key(p.proxy_a, p.proxy_b));
  if (p.cache == kNoIndex) return;
  free_manifolds(caches[p.cache]);
  if (caches[p.cache].mesh_query != kNoIndex) free_mesh_queries.push_back(caches[p.cache].mesh_query);
  caches[p.cache].first = free_cache;
  free_cache = p.cache;
  p.cache = kNoIndex;
}

// ---------------------------------------------------------------------------------------
// the broad phase

double RigidContacts::turn_travel(const RigidBodySystem& s, std::size_t i) {
  return s.w_[i] == Vec3(0) ? 0.0 : std::min(glm::length(s.w_[i]) * s.extent_[i] * s.last_dt_, s.extent_[i]);
}

void RigidContacts::update_proxies(RigidBodySystem& s, double dt) {
  const ContactSettings& cs = s.settings_;
  const std::size_t n = s.type_.size();
  moved.clear(), moved_box.clear(), moved_keys.clear();
  std::size_t created = 0;
  // bodies added since the last step (a scene's first step: all of them): what their shapes
  // grow is sized here once, not doubled as they come (a doubling's copy lands on pages the
  // process has not touched, and the rain's first step spent more on those faults than on
  // the copies)
  if (n > bodies_seen) {
    std::size_t shapes = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t slot = s.owner_[i];
      if (slot >= body_proxies.size() || body_proxies[slot].empty()) shapes += s.shapes_[i].size();
    }
    // at least doubled (reserve() alone gives the exact size: a body added each step would copy
    // every proxy each step)
    const auto grow = [](auto& v, std::size_t need) {
      if (need > v.capacity()) v.reserve(std::max(need, 2 * v.capacity()));
    };
    grow(body_proxies, s.slot_.size());
    grow(proxies, proxies.size() + shapes);
    grow(moved, proxies.capacity()), grow(moved_box, proxies.capacity()), grow(moved_keys, proxies.capacity());
    tree.reserve(tree.proxy_count() + shapes);
  }
  bodies_seen = n;
  // A body's boxes reach out as far as any of its pairs' speculative points can: the setting,
  // or when a pair's is less (pair_speculative: kSpeculativePerHalfSize of the thinner body's
  // smallest half size plus both bodies' turn) the body's own share of it, kSpeculativePerHalfSize
  // of its smallest half size plus its turn (a plane or a mesh, never the thinner body of a
  // pair, its turn alone); two bodies' shares add up to at least their pair's reach. Grown by
  // the setting alone, a speculative_distance of metres made every pair of a scene whose
  // points it then cut to their pair's reach (1,728 boxes at 1000 m: 1.3 s a step and not one
  // manifold). Only when some body, static ones too, may take less (`thinnest`): else the
  // setting. The AVX2 fours below take the setting's reach: four bodies none of which takes less
  // whatever its turn.
  const bool share = kSpeculativePerHalfSize * thinnest < cs.speculative_distance;
  [[maybe_unused]] auto setting_reach4 = [&](std::size_t i) {
    for (std::size_t k = i; k < i + 4; ++k)
      if (kSpeculativePerHalfSize * s.min_extent_[k] < cs.speculative_distance) return false;
    return true;
  };
  auto speculative = [&](std::size_t i) {
    if (!share) return cs.speculative_distance;
    const double thin = s.min_extent_[i], own = std::isinf(thin) ? 0.0 : kSpeculativePerHalfSize * thin;
    return std::min(cs.speculative_distance, own + turn_travel(s, i));
  };
  // on AVX2 the bodies go by fours through proxies4_avx2 where it takes them (the plain path
  // and AVX-512 one by one, as before); after a four it turns down, the next try is twice as
  // far ahead, up to 64 bodies, so that a scene of other shapes or sleepers pays for few tries
#if PBA_EMIT_AVX2
  std::size_t next4 = simd == SimdPath::Avx2 ? 0 : n, back_off = 4;
#endif
  for (std::size_t i = 0; i < n; ++i) {
#if PBA_EMIT_AVX2
    if (i == next4) {
      if (i + 4 <= n && (!share || setting_reach4(i)) && proxies4_avx2(s, i, dt)) {
        next4 = i + 4, back_off = 4;
        i += 3;
        continue;
      }
      next4 = i + back_off, back_off = std::min<std::size_t>(2 * back_off, 64);
    }
#endif
    // a body's shapes sit in a block of their own (a vector per body): the first one's lines
    // asked for some bodies ahead (its type, size and local pose: 216 bytes)
    if (i + kBodiesAhead < n) prefetch_lines<sizeof(RigidShapeDef)>(s.shapes_[i + kBodiesAhead].data());
    const std::uint32_t slot = s.owner_[i];
    if (slot >= body_proxies.size()) body_proxies.resize(slot + 1);
    std::vector<std::uint32_t>& mine = body_proxies[slot];
    const bool fresh = mine.empty();
    const BodyType type = s.type_[i];
    // (a still body, as every sleeping one is, travels 0, its speed's square root unmade)
    const double speed = s.v_[i] == Vec3(0) ? 0.0 : glm::length(s.v_[i]);
    travel[i] = std::min(speed * dt, s.extent_[i]);
    // a sleeping body does not move, nor does a static one that was not put elsewhere (its
    // pose, a normalised product, is made only past the sleepers)
    if (!fresh && type == BodyType::Dynamic && s.asleep_[i]) continue;
    // (body_pose and shape_frame skip the products by identities where they give the same bits)
    const Pose body = s.body_pose(i);
    if (type == BodyType::Static) {
      // (by slot, as far as the static bodies' slots reach: a 10,000-body scene's first step
      // wrote 560 KB of poses for its one ground)
      if (slot >= static_pose.size()) static_pose.resize(slot + 1);
      const Pose& was = static_pose[slot];
      if (!fresh && was.position == body.position && was.rotation == body.rotation) continue;
      static_pose[slot] = body;
    }
    // the tight bounds reach as far as the body can move in the step, and the fat ones two
    // steps' travel ahead, both up to the body's own size (the continuous pass catches faster
    // bodies; fat boxes stretched further fill the pair list)
    const double reach = speculative(i) + travel[i];
    const Vec3 ahead = type == BodyType::Static || speed == 0 ? Vec3(0)
                                                                : std::min(2 * speed * dt, s.extent_[i]) / speed * s.v_[i];
    for (std::uint32_t k = 0; k < s.shapes_[i].size(); ++k) {
      if (fresh) {
        std::uint32_t q = free_proxy;
        if (q != kNoIndex) {
          free_proxy = proxies[q].body;
        } else {
          q = static_cast<std::uint32_t>(proxies.size());
          proxies.emplace_back();
          // (the poses grow with the proxies, which grow only here)
          if (shape_poses.size() < proxies.size())
            shape_poses.resize(proxies.capacity()), shape_pose_stamp.resize(proxies.capacity(), 0);
        }
        mine.push_back(q);
      }
      const std::uint32_t q = mine[k];
      ShapeProxy& p = proxies[q];
      shape_poses[q] = shape_frame(body, s.shapes_[i][k].local);
      shape_pose_stamp[q] = stamp;
      // (a ball's and a box's bounds inline: as calls, with rotated_half's, they cost the rain's
      // landing step 0.65 M instructions more, 9% of this function's)
      p.box = shape_bounds(s.shapes_[i][k].shape, shape_poses[q]).grown(reach);
      p.body = static_cast<std::uint32_t>(i), p.shape = k, p.slot = slot;
      const bool bounded = is_finite(p.box.lo) && is_finite(p.box.hi);
      if (fresh) {
        // a new shape: into the tree (a plane into the unbounded list) and queried
        // (from the 17th new shape of a step on, the tree is rebuilt below: the leaf waits
        // for it unplaced, not searched for a place that the rebuild throws away; 10,000
        // insertions were a third of the rain's first step's instructions)
        if (bounded && created >= kCreatedBeforeRebuild) {
          p.node = tree.create_proxy_unplaced(stretched(p.box, ahead), q);
          p.fat = tree.fat_box(p.node);
        } else if (bounded) {
          p.node = tree.create_proxy(stretched(p.box, ahead), q);
          p.fat = tree.fat_box(p.node);
        } else {
          p.node = -1, p.fat = p.box;
          unbounded.push_back(q);
        }
        if (type == BodyType::Static) statics.push_back(q);
        moved_keys.push_back(moved.size());
        moved_box.push_back(p.fat);  // (never read: lines up with moved)
        moved.push_back(q);
        ++created;
      } else if (p.node >= 0) {
        // it left its fat box: a new one, and a query for new pairs. A fat box that has grown
        // more than a margin too large on some side (stretched while the body fell fast, now
        // at rest) is made anew too, or it would keep pairs that cannot touch; behind a moving
        // body, it may trail by the travel it is stretched ahead by (else a body falling
        // faster than a margin a step left its fat box behind every step: the 10,000-body
        // rain re-inserted all its proxies every step of its fall, 6 ms a step)
        // (the leaf keeps its place in the tree, only its box and its ancestors' change: a
        // search for a new place, with the removal and the rotations on both walks, cost the
        // rain 1,900 re-insertions a step, all 10,000 every third step of its fall; the tree's
        // quality is watched below)
        // (the leaf's new box is set below, with the others', in the tree's order: a new shape
        // inserted meanwhile finds its place among the old boxes, which moves no pair)
        const Aabb want = stretched(p.box, ahead);
        if (p.fat.contains(p.box) && stretched(want, -ahead).grown(2 * tree.margin()).contains(p.fat)) continue;
        moved_keys.push_back(std::uint64_t{1} << 31 | moved.size());
        moved_box.push_back(want);
        moved.push_back(q);
      } else {
        // a plane put elsewhere
        p.fat = p.box;
        moved_keys.push_back(moved.size());
        moved_box.push_back(p.fat);  // (never read: lines up with moved)
        moved.push_back(q);
      }
    }
  }
  // many insertions at once (the first step of a scene) are better rebuilt than kept; moves
  // wear the tree down, so its quality is checked now and then (BroadPhase does the same)
  const bool rebuild_all = created > kCreatedBeforeRebuild;
  // the leaves' new boxes, in the tree's order (but for a rebuild below: in any order, as the
  // inner boxes are unions, and the entries are put in the rebuilt tree's order after it)
  if (rebuild_all) {
    for (std::size_t i = 0; i < moved.size(); ++i)
      if (moved_keys[i] >> 31 & 1) set_moved_box(i);
  } else {
    tree_order(true);
  }
  reinserted_since_check += moved.size();
  bool rebuilt = false;
  if (rebuild_all) {
    tree.rebuild();
    tree_ratio = tree.area_ratio();
    reinserted_since_check = 0;
    rebuilt = true;
  } else if (reinserted_since_check > tree.proxy_count() && tree.proxy_count() > 2) {
    const double ratio = tree.area_ratio();
    if (ratio > 1.5 * tree_ratio) {
      tree.rebuild();
      tree_ratio = tree.area_ratio();
      rebuilt = true;
    }
    reinserted_since_check = 0;
  }
  // (the queries go in the order of the tree they walk)
  if (rebuilt) {
    for (std::size_t i = 0; i < moved.size(); ++i) moved_keys[i] = i;
    tree_order(false);
  }
}

#if PBA_EMIT_AVX2
namespace {
// the lanes whose double's exponent is `e`: 0 (a zero or a subnormal) or all ones (infinite or
// NaN), which exact_times_identity() turns down
[[gnu::target("avx2")]] inline __m256i exponent_is(__m256d x, long long e) {
  const __m256i ones = _mm256_set1_epi64x(0x7ff0000000000000);
  return _mm256_cmpeq_epi64(_mm256_and_si256(_mm256_castpd_si256(x), ones), _mm256_set1_epi64x(e));
}
[[gnu::target("avx2")]] inline __m256i any_exponent_is(const __m256d q[4], long long e) {
  return _mm256_or_si256(_mm256_or_si256(exponent_is(q[0], e), exponent_is(q[1], e)),
                         _mm256_or_si256(exponent_is(q[2], e), exponent_is(q[3], e)));
}

// glm's p * q of 4 quaternions (w, x, y, z by lane), its sums in its order
[[gnu::target("avx2")]] inline void times_lanes(const __m256d p[4], const __m256d q[4], __m256d out[4]) {
  out[0] = _mm256_sub_pd(
      _mm256_sub_pd(_mm256_sub_pd(_mm256_mul_pd(p[0], q[0]), _mm256_mul_pd(p[1], q[1])), _mm256_mul_pd(p[2], q[2])),
      _mm256_mul_pd(p[3], q[3]));
  out[1] = _mm256_sub_pd(
      _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(p[0], q[1]), _mm256_mul_pd(p[1], q[0])), _mm256_mul_pd(p[2], q[3])),
      _mm256_mul_pd(p[3], q[2]));
  out[2] = _mm256_sub_pd(
      _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(p[0], q[2]), _mm256_mul_pd(p[2], q[0])), _mm256_mul_pd(p[3], q[1])),
      _mm256_mul_pd(p[1], q[3]));
  out[3] = _mm256_sub_pd(
      _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(p[0], q[3]), _mm256_mul_pd(p[3], q[0])), _mm256_mul_pd(p[1], q[2])),
      _mm256_mul_pd(p[2], q[1]));
}

// glm::normalize of 4 quaternions (components by lane): the same products and sums in the
// same order, the identity where the length is not > 0
[[gnu::target("avx2")]] inline void normalize_lanes(__m256d q[4]) {
  // q: w, x, y, z; glm's dot sums (ww + xx) + (yy + zz)
  const __m256d dot = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(q[0], q[0]), _mm256_mul_pd(q[1], q[1])),
                                    _mm256_add_pd(_mm256_mul_pd(q[2], q[2]), _mm256_mul_pd(q[3], q[3])));
  const __m256d len = _mm256_sqrt_pd(dot);
  const __m256d zero = _mm256_setzero_pd();
  const __m256d none = _mm256_cmp_pd(len, zero, _CMP_LE_OQ);
  const __m256d inv = _mm256_div_pd(_mm256_set1_pd(1.0), len);
  q[0] = _mm256_blendv_pd(_mm256_mul_pd(q[0], inv), _mm256_set1_pd(1.0), none);
  for (int k = 1; k < 4; ++k) q[k] = _mm256_blendv_pd(_mm256_mul_pd(q[k], inv), zero, none);
}
// glm::mat3_cast of four quaternions (w, x, y, z, a lane each), its products and sums in its
// order (the same bits), by column: m[j][i] is column j's row i, as a Mat3 holds them
[[gnu::always_inline]] __attribute__((target("avx2"))) inline void mat3_cast4(__m256d w, __m256d x, __m256d y,
                                                                           __m256d z, __m256d (&m)[3][3]) {
  const __m256d xx = _mm256_mul_pd(x, x), yy = _mm256_mul_pd(y, y), zz = _mm256_mul_pd(z, z);
  const __m256d xz = _mm256_mul_pd(x, z), xy = _mm256_mul_pd(x, y), yz = _mm256_mul_pd(y, z);
  const __m256d wx = _mm256_mul_pd(w, x), wy = _mm256_mul_pd(w, y), wz = _mm256_mul_pd(w, z);
  const __m256d one = _mm256_set1_pd(1.0), two = _mm256_set1_pd(2.0);
  m[0][0] = _mm256_sub_pd(one, _mm256_mul_pd(two, _mm256_add_pd(yy, zz)));
  m[0][1] = _mm256_mul_pd(two, _mm256_add_pd(xy, wz));
  m[0][2] = _mm256_mul_pd(two, _mm256_sub_pd(xz, wy));
  m[1][0] = _mm256_mul_pd(two, _mm256_sub_pd(xy, wz));
  m[1][1] = _mm256_sub_pd(one, _mm256_mul_pd(two, _mm256_add_pd(xx, zz)));
  m[1][2] = _mm256_mul_pd(two, _mm256_add_pd(yz, wx));
  m[2][0] = _mm256_mul_pd(two, _mm256_add_pd(xz, wy));
  m[2][1] = _mm256_mul_pd(two, _mm256_sub_pd(yz, wx));
  m[2][2] = _mm256_sub_pd(one, _mm256_mul_pd(two, _mm256_add_pd(xx, yy)));
}
}  // namespace

// The loop of update_proxies for 4 bodies, each through the float operations it makes for
// one, in the same order, with the same identities left out (body_frame, shape_frame), so with
// the same bits: the body's travel, its rotation normalised twice (body_frame's, then
// shape_frame's), the shape's tight box (a ball's or a box's, rotated_half's sums), the
// stretch ahead and the fat-box test. (On fall1000 this function made about 700 scalar
// instructions a body; the tests that pick the case and the loads stay scalar.)
[[gnu::target("avx2")]] bool RigidContacts::proxies4_avx2(RigidBodySystem& s, std::size_t i, double dt) {
  constexpr int L = 4;
  ShapeProxy* proxy[L];
  std::uint32_t index[L], slots[L];
  alignas(32) double in[23][L];  // v (3), com (3), q (w x y z), extent, half extents (3), ball radius, principal, local turn
  alignas(32) double fat_box[6][L];
  int ball = 0;
  for (int j = 0; j < L; ++j) {
    const std::size_t b = i + static_cast<std::size_t>(j);
    const std::uint32_t slot = s.owner_[b];
    if (s.type_[b] != BodyType::Dynamic || s.asleep_[b] || slot >= body_proxies.size() ||
        body_proxies[slot].size() != 1 || s.shapes_[b].size() != 1)
      return false;
    const RigidShapeDef& def = s.shapes_[b][0];
    const ShapeType type = def.shape.type;
    if (!((type == ShapeType::Sphere) | (type == ShapeType::Box)) ||
        !(positive_zero(def.local.position) & is_identity(def.local.rotation) & is_identity(s.principal_[b]) &
          positive_zero(s.com_local_[b])))
      return false;
    const std::uint32_t q = body_proxies[slot][0];
    if (proxies[q].node < 0) return false;
    proxy[j] = &proxies[q], index[j] = q, slots[j] = slot;
    ball |= (type == ShapeType::Sphere) << j;
    const Vec3& v = s.v_[b];
    const Vec3& c = s.com_[b];
    const Quat& r = s.q_[b];
    in[0][j] = v.x, in[1][j] = v.y, in[2][j] = v.z;
    in[3][j] = c.x, in[4][j] = c.y, in[5][j] = c.z;
    in[6][j] = r.w, in[7][j] = r.x, in[8][j] = r.y, in[9][j] = r.z;
    in[10][j] = s.extent_[b];
    in[11][j] = def.shape.half_extents.x, in[12][j] = def.shape.half_extents.y, in[13][j] = def.shape.half_extents.z;
    in[14][j] = def.shape.radius;
    const Quat& principal = s.principal_[b];
    in[15][j] = principal.w, in[16][j] = principal.x, in[17][j] = principal.y, in[18][j] = principal.z;
    in[19][j] = def.local.rotation.w, in[20][j] = def.local.rotation.x, in[21][j] = def.local.rotation.y;
    in[22][j] = def.local.rotation.z;
    const Aabb& f = proxy[j]->fat;
    fat_box[0][j] = f.lo.x, fat_box[1][j] = f.lo.y, fat_box[2][j] = f.lo.z;
    fat_box[3][j] = f.hi.x, fat_box[4][j] = f.hi.y, fat_box[5][j] = f.hi.z;
  }
  const __m256d zero = _mm256_setzero_pd();
  __m256d rot[4] = {_mm256_load_pd(in[6]), _mm256_load_pd(in[7]), _mm256_load_pd(in[8]), _mm256_load_pd(in[9])};
  // body_frame leaves q conjugate(principal) out only for q's with every component plain, and
  // shape_frame compose(body, local) only for such a normalised q: the lanes with a zero (an
  // unturned body: fall1000's cubes until they first touch) take the products, as there; an
  // infinite or NaN component goes one by one (the positions' products by the zero vectors
  // are +0 only for finite turns)
  constexpr long long kZero = 0, kSpecial = 0x7ff0000000000000;
  for (int turn = 0; turn < 2; ++turn) {
    const __m256i special = any_exponent_is(rot, kSpecial);
    if (!_mm256_testz_si256(special, special)) return false;
    const __m256i zeros = any_exponent_is(rot, kZero);
    __m256d plain[4] = {rot[0], rot[1], rot[2], rot[3]};
    normalize_lanes(plain);
    if (_mm256_testz_si256(zeros, zeros)) {
      for (int k = 0; k < 4; ++k) rot[k] = plain[k];
      continue;
    }
    // body_frame's q conjugate(principal), shape_frame's (compose's) r local.rotation
    const int from = turn == 0 ? 15 : 19;
    const __m256d flip = _mm256_set1_pd(turn == 0 ? -0.0 : 0.0);
    const __m256d by[4] = {_mm256_load_pd(in[from]), _mm256_xor_pd(_mm256_load_pd(in[from + 1]), flip),
                           _mm256_xor_pd(_mm256_load_pd(in[from + 2]), flip),
                           _mm256_xor_pd(_mm256_load_pd(in[from + 3]), flip)};
    __m256d product[4];
    times_lanes(rot, by, product);
    normalize_lanes(product);
    for (int k = 0; k < 4; ++k) rot[k] = _mm256_blendv_pd(plain[k], product[k], _mm256_castsi256_pd(zeros));
  }

  const __m256d vx = _mm256_load_pd(in[0]), vy = _mm256_load_pd(in[1]), vz = _mm256_load_pd(in[2]);
  const __m256d extent = _mm256_load_pd(in[10]);
  // speed: 0 for a still body (v == 0), else glm::length's (xx + yy) + zz, its root
  const __m256d still = _mm256_and_pd(_mm256_and_pd(_mm256_cmp_pd(vx, zero, _CMP_EQ_OQ), _mm256_cmp_pd(vy, zero, _CMP_EQ_OQ)),
                                      _mm256_cmp_pd(vz, zero, _CMP_EQ_OQ));
  const __m256d length = _mm256_sqrt_pd(
      _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(vx, vx), _mm256_mul_pd(vy, vy)), _mm256_mul_pd(vz, vz)));
  const __m256d speed = _mm256_blendv_pd(length, zero, still);
  const __m256d vdt = _mm256_set1_pd(dt);
  // std::min(a, b) is (b < a ? b : a), vminpd(b, a)
  const __m256d moves = _mm256_min_pd(extent, _mm256_mul_pd(speed, vdt));
  _mm256_storeu_pd(&travel[i], moves);
  const __m256d reach = _mm256_add_pd(_mm256_set1_pd(s.settings_.speculative_distance), moves);
  // ahead: std::min(2 speed dt, extent) / speed times v, 0 for speed 0
  const __m256d scale =
      _mm256_div_pd(_mm256_min_pd(extent, _mm256_mul_pd(_mm256_mul_pd(_mm256_set1_pd(2.0), speed), vdt)), speed);
  const __m256d halted = _mm256_cmp_pd(speed, zero, _CMP_EQ_OQ);
  const __m256d ahead[3] = {_mm256_blendv_pd(_mm256_mul_pd(scale, vx), zero, halted),
                            _mm256_blendv_pd(_mm256_mul_pd(scale, vy), zero, halted),
                            _mm256_blendv_pd(_mm256_mul_pd(scale, vz), zero, halted)};

  // the box's world half widths (rotated_half: glm::mat3_cast's entries, the sums from 0 by
  // columns), a ball's radius instead in its lanes
  const __m256d sign = _mm256_set1_pd(-0.0);
  __m256d m[3][3];  // r[j][i], j the column
  mat3_cast4(rot[0], rot[1], rot[2], rot[3], m);
  const __m256d h[3] = {_mm256_load_pd(in[11]), _mm256_load_pd(in[12]), _mm256_load_pd(in[13])};
  const __m256d radius = _mm256_load_pd(in[14]);
  const __m256d balls = _mm256_castsi256_pd(
      _mm256_cmpeq_epi64(_mm256_and_si256(_mm256_set1_epi64x(ball), _mm256_setr_epi64x(1, 2, 4, 8)), _mm256_setr_epi64x(1, 2, 4, 8)));
  alignas(32) double out[9][L];  // position (3), box lo (3), hi (3)
  alignas(32) double want[6][L];
  __m256d keep = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
  const __m256d margin = _mm256_set1_pd(2 * tree.margin());
  const __m256d com[3] = {_mm256_load_pd(in[3]), _mm256_load_pd(in[4]), _mm256_load_pd(in[5])};
  for (int c = 0; c < 3; ++c) {
    __m256d half = zero;
    for (int j = 0; j < 3; ++j) half = _mm256_add_pd(half, _mm256_mul_pd(_mm256_andnot_pd(sign, m[j][c]), h[j]));
    half = _mm256_blendv_pd(half, radius, balls);
    // shape_frame's position: body.position + 0
    const __m256d at = _mm256_add_pd(com[c], zero);
    const __m256d lo = _mm256_sub_pd(_mm256_sub_pd(at, half), reach);
    const __m256d hi = _mm256_add_pd(_mm256_add_pd(at, half), reach);
    _mm256_store_pd(out[c], at), _mm256_store_pd(out[3 + c], lo), _mm256_store_pd(out[6 + c], hi);
    // stretched(box, ahead) (glm::min(a, 0) is (0 < a ? 0 : a), vminpd(0, a); max alike), and
    // the test: fat contains box, and stretched(want, -ahead) grown by 2 margins contains fat
    const __m256d want_lo = _mm256_add_pd(lo, _mm256_min_pd(zero, ahead[c]));
    const __m256d want_hi = _mm256_add_pd(hi, _mm256_max_pd(zero, ahead[c]));
    _mm256_store_pd(want[c], want_lo), _mm256_store_pd(want[3 + c], want_hi);
    const __m256d back = _mm256_xor_pd(ahead[c], sign);
    const __m256d far_lo = _mm256_sub_pd(_mm256_add_pd(want_lo, _mm256_min_pd(zero, back)), margin);
    const __m256d far_hi = _mm256_add_pd(_mm256_add_pd(want_hi, _mm256_max_pd(zero, back)), margin);
    const __m256d fat_lo = _mm256_load_pd(fat_box[c]), fat_hi = _mm256_load_pd(fat_box[3 + c]);
    keep = _mm256_and_pd(keep, _mm256_and_pd(_mm256_cmp_pd(fat_lo, lo, _CMP_LE_OQ), _mm256_cmp_pd(hi, fat_hi, _CMP_LE_OQ)));
    keep = _mm256_and_pd(keep, _mm256_and_pd(_mm256_cmp_pd(far_lo, fat_lo, _CMP_LE_OQ), _mm256_cmp_pd(fat_hi, far_hi, _CMP_LE_OQ)));
  }
  alignas(32) double turn[4][L];
  for (int k = 0; k < 4; ++k) _mm256_store_pd(turn[k], rot[k]);
  // the bodies' rotation matrices for emit (rotation()): glm::mat3_cast of q_ as it stands (not
  // normalised), its products and sums in its order, so the same bits. Made by the emit that
  // first needed one, a matrix stored a double at a time was loaded back two at a time, which
  // waits for the stores to leave (after those loads sat 17% of emit's samples on the 2870
  // pyramid); made here, it has long left when emit reads it
  alignas(32) double turned[9][L];
  {
    __m256d r[3][3];
    mat3_cast4(_mm256_load_pd(in[6]), _mm256_load_pd(in[7]), _mm256_load_pd(in[8]), _mm256_load_pd(in[9]), r);
    for (int e = 0; e < 9; ++e) _mm256_store_pd(turned[e], r[e / 3][e % 3]);
  }
  const int kept = _mm256_movemask_pd(keep);
  for (int j = 0; j < L; ++j) {
    const std::size_t b = i + static_cast<std::size_t>(j);
    if (b + kBodiesAhead < s.type_.size()) prefetch_lines<sizeof(RigidShapeDef)>(s.shapes_[b + kBodiesAhead].data());
    double* matrix = &rotations[b][0][0];
    for (int e = 0; e < 9; ++e) matrix[e] = turned[e][j];
    rotation_stamp[b] = stamp;
    const std::uint32_t q = index[j];
    ShapeProxy& p = *proxy[j];
    shape_poses[q] = {Vec3(out[0][j], out[1][j], out[2][j]), Quat(turn[0][j], turn[1][j], turn[2][j], turn[3][j])};
    shape_pose_stamp[q] = stamp;
    p.box = {Vec3(out[3][j], out[4][j], out[5][j]), Vec3(out[6][j], out[7][j], out[8][j])};
    p.body = static_cast<std::uint32_t>(b), p.shape = 0, p.slot = slots[j];
    if (kept >> j & 1) continue;
    moved_keys.push_back(std::uint64_t{1} << 31 | moved.size());
    moved_box.push_back({Vec3(want[0][j], want[1][j], want[2][j]), Vec3(want[3][j], want[4][j], want[5][j])});
    moved.push_back(q);
  }
  return true;
}
#endif

// Puts `moved` in the order of its leaves' parents' indices, stably (`moved_keys[i]`: entry
// i, with bit 31 set when its leaf is to get the fat box of `moved_box[i]`, which is set on
// the way when `set_boxes`; planes go last). A rebuild allocates a subtree's inner nodes one
// after the other (build_range: children before their parent), so leaves close in this order
// are close in the tree, and the moved proxies' leaf updates and queries walk the same few
// nodes one after another instead of the whole tree each (in body order, the rain's
// neighbours in a heap are its columns' four layers, 2,500 bodies apart). Nothing the tree
// or the queries find depends on the order (each inner box is the union of its children's
// whatever order its leaves are set in; the pair set and the sorted new pairs do not depend on
// the order of the queries): only where the waits fall does.
void RigidContacts::tree_order(bool set_boxes) {
  const std::size_t m = moved.size();
  if (m == 0) return;
  const std::span<const DynamicTree::Node> nodes = tree.nodes();
  const auto last = static_cast<std::uint32_t>(nodes.size());
  for (std::size_t i = 0; i < m; ++i) {
    const std::int32_t leaf = proxies[moved[i]].node;
    const std::int32_t parent = leaf >= 0 ? nodes[static_cast<std::size_t>(leaf)].parent : DynamicTree::kNull;
    const std::uint32_t key = parent >= 0 ? static_cast<std::uint32_t>(parent) : last;
    moved_keys[i] |= std::uint64_t{key} << 32;
  }
  // (two passes for the rain's 20,000 nodes)
  sort_by_high_word(moved_keys, moved_keys_spare, static_cast<int>(std::bit_width(last)));
  moved_spare.clear();
  if (set_boxes && was_moved.size() < proxies.size()) was_moved.resize(proxies.size(), 0);
  for (const std::uint64_t k : moved_keys) {
    const std::size_t i = k & 0x7fffffffu;
    if (set_boxes && (k >> 31 & 1)) {
      // a fat box made anew within the one it replaces (as set_leaf_box grows it: the same
      // bits) overlaps no box its old one did not: find_new_pairs does not query it (2)
      const ShapeProxy& p = proxies[moved[i]];
      if (p.fat.contains(moved_box[i].grown(tree.margin()))) was_moved[moved[i]] = 2;
      set_moved_box(i);
    }
    moved_spare.push_back(moved[i]);
  }
  moved.swap(moved_spare);
}

void RigidContacts::find_new_pairs(RigidBodySystem& s) {
  found.clear();
  if (was_moved.size() < proxies.size()) was_moved.resize(proxies.size(), 0);
  // A moved proxy whose new fat box lies within its old one (tree_order marked it 2: a body
  // slowing down, its box stretched ahead less) is not queried: every proxy its box overlaps
  // now overlapped its old box, and each pair of overlapping fat boxes is in the list (found
  // when one of them last moved, ended only when they part; two such proxies overlapped
  // before as well). A proxy that did query and hits it keeps the pair from its side (1: the
  // proxies that query). The pair set and the sorted new pairs are those the queries made.
  // (In the rain's landing, of the 1,200-4,400 proxies moved a step, the queries left out
  // were 0.30 of their 3.96 M instructions a step: docs/benchmarks.md, rain6.)
  for (const std::uint32_t p : moved)
    if (was_moved[p] != 2) was_moved[p] = 1;
  // In three passes, each in the order of the last (so the pair set sees the same keys in the
  // same order as one pass would give it): the queries, listing what each moved proxy's fat
  // box overlaps; the filters, reading each hit proxy's entry; the pair set. One pass waited
  // on each of them in turn (the proxy hit and the pair set's slot are anywhere in memory:
  // 1,500-2,500 moved proxies a landing step of the rain); apart, each is fetched some hits
  // ahead.
  // The moved leaves' pairs by one walk of the tree against itself (query_pairs), each pair
  // once: a hit names a moved proxy first, the lower when both moved, as the filters below
  // keep it (a query of each moved leaf found the pairs of two moved ones from both sides, and
  // walked the top of the tree once a leaf: the rain's first step queried 10,000 leaves, 9.9 M
  // instructions). A moved plane queries the tree as before. The hits' order changes, not
  // their set: the pair set holds the same keys, and the new pairs are sorted below.
  // Only when at least half the leaves moved (the first step, the fall's steps that move
  // them all): with fewer the walk pairs about as many nodes as the queries visit at twice
  // the cost a node (the landing's 13-25%: find_new_pairs 5.8 M instructions a step by the
  // queries, 8.5 M by the walk).
  hits.clear();
  moved_leaves.clear();
  for (const std::uint32_t p : moved)
    if (proxies[p].node >= 0 && was_moved[p] == 1) moved_leaves.push_back(proxies[p].node);
  const bool walk = 2 * moved_leaves.size() >= tree.proxy_count();
  if (walk)
    tree.query_pairs(moved_leaves, [&](std::uint32_t a, std::uint32_t b) {
      const bool a_first = was_moved[a] == 1 && (was_moved[b] != 1 || a < b);
      hits.push_back(a_first ? std::uint64_t{a} << 32 | b : std::uint64_t{b} << 32 | a);
    });
  for (const std::uint32_t p : moved) {
    if (was_moved[p] != 1) continue;
    const ShapeProxy& P = proxies[p];
    if (P.node < 0 || !walk) {
      tree.query(P.fat, [&](std::uint32_t q) {
        hits.push_back(std::uint64_t{p} << 32 | q);
        return true;
      });
    }
    for (const std::uint32_t u : unbounded)
      if (proxies[u].fat.overlaps(P.fat)) hits.push_back(std::uint64_t{p} << 32 | u);
  }
  constexpr std::size_t kAhead = 8;
  candidates.clear();
  for (std::size_t i = 0; i < hits.size(); ++i) {
    if (i + kAhead < hits.size()) {
      const auto ahead = static_cast<std::uint32_t>(hits[i + kAhead]);
      __builtin_prefetch(&proxies[ahead].body);
    }
    const auto p = static_cast<std::uint32_t>(hits[i] >> 32), q = static_cast<std::uint32_t>(hits[i]);
    const ShapeProxy& P = proxies[p];
    const ShapeProxy& Q = proxies[q];
    // not with itself, not two bodies that cannot move each other, and two moved shapes
    // once (from the lower proxy)
    if (Q.slot == P.slot || (s.inv_mass_[P.body] == 0 && s.inv_mass_[Q.body] == 0)) continue;
    if (was_moved[q] == 1 && q < p) continue;
    const bool swap = P.slot > Q.slot;
    const ShapeProxy& A = swap ? Q : P;
    const ShapeProxy& B = swap ? P : Q;
    candidates.push_back({A.slot, B.slot, A.shape, B.shape, swap ? q : p, swap ? p : q, kNoIndex});
  }
  // only pairs the list does not hold yet (each found once)
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (i + kAhead < candidates.size()) {
      const ShapePair& ahead = candidates[i + kAhead];
      pair_set.prefetch(pair_key(ahead.proxy_a, ahead.proxy_b));
    }
    const ShapePair& c = candidates[i];
    if (pair_set.insert(pair_key(c.proxy_a, c.proxy_b))) {
      found.push_back(c);
      ShapePair& f = found.back();
      f.type_a = s.shapes_[proxies[c.proxy_a].body][c.shape_a].shape.type;
      f.type_b = s.shapes_[proxies[c.proxy_b].body][c.shape_b].shape.type;
    }
  }
  for (const std::uint32_t p : moved) was_moved[p] = 0;
  if (found.empty()) return;
  // the new ones, sorted, merged into the list
  std::sort(found.begin(), found.end());
  merged.clear();
  std::merge(shape_pairs.begin(), shape_pairs.end(), found.begin(), found.end(), std::back_inserter(merged));
  shape_pairs.swap(merged);
}

// A body moving faster than the sleep tolerances (or a moving kinematic one) whose bounds
// reach a sleeping body wakes its island. A slow awake body does not: it rests on the sleeper
// as on a static body (waking on any overlap let two slow neighbours wake each other forever).
// A dynamic body that set_pose moved since the last step counts as moving, once, for the
// sleepers it touches (the narrow phase finds a point closer than the speculative distance):
// a teleport has no velocity, and one into a sleeping stack left the stack asleep, holding
// still like a static body while the solver pushed the teleported body alone out of it
// (Box2D v3 wakes a sleeping body when a contact with it begins touching); a sleeper whose
// bounds it only reaches (a ball by a box's corner) sleeps on. A woken body is still (sleep
// zeroed its velocity), so one pass wakes all that this step can.
void RigidContacts::wake_touched(RigidBodySystem& s) {
  const ContactSettings& cs = s.settings_;
  auto forget_jumped = [&] {
    for (const std::uint32_t slot : jumped) jumped_slot[slot] = 0;
    jumped.clear();
  };
  if (std::find(s.asleep_.begin(), s.asleep_.end(), std::uint8_t{1}) == s.asleep_.end()) {
    forget_jumped();
    return;
  }
  // the bodies that jumped, by dense index (a slot destroyed since, or taken by another body
  // since, is skipped, or wakes what that body touches: harmless)
  const std::size_t n = s.type_.size();
  // the sleepers a jumped body wakes are listed after these for the next step (one island a
  // step up a chain of sleeping islands: their bodies are still, so as moving bodies they
  // would wake nothing)
  const std::size_t listed = jumped.size();
  if (listed > 0) {
    if (jumped_flag.size() < n) jumped_flag.resize(n, 0);
    for (const std::uint32_t slot : jumped)
      if (slot < s.slot_.size() && s.slot_[slot] < n && s.owner_[s.slot_[slot]] == slot) jumped_flag[s.slot_[slot]] = 1;
  }
  const double lin2 = cs.sleep_linear * cs.sleep_linear, ang2 = cs.sleep_angular * cs.sleep_angular;
  // 0: not moving; 1: moving (faster than the tolerances, or a moving kinematic body);
  // 2: only teleported (wakes what it touches)
  auto moving = [&](std::uint32_t i) {
    const double v2 = glm::dot(s.v_[i], s.v_[i]), w2 = glm::dot(s.w_[i], s.w_[i]);
    if (s.type_[i] == BodyType::Dynamic) {
      if (s.asleep_[i]) return 0;
      if (v2 > lin2 || w2 > ang2) return 1;
      return listed > 0 && jumped_flag[i] ? 2 : 0;
    }
    return s.type_[i] == BodyType::Kinematic && (v2 > 0 || w2 > 0) ? 1 : 0;
  };
  for (const ShapePair& p : shape_pairs) {
    const std::uint32_t a = s.slot_[p.slot_a], b = s.slot_[p.slot_b];
    if (s.asleep_[a] == s.asleep_[b]) continue;
    const bool a_sleeps = s.asleep_[a];
    const std::uint32_t sleeper = a_sleeps ? a : b, other = a_sleeps ? b : a;
    const int how = moving(other);
    if (how == 0 || !proxies[p.proxy_a].box.overlaps(proxies[p.proxy_b].box)) continue;
    if (how == 2 && !s.shapes_touch(other, a_sleeps ? p.shape_b : p.shape_a, sleeper, a_sleeps ? p.shape_a : p.shape_b))
      continue;
    if (how == 2)
      s.wake_island_listed(sleeper);
    else
      s.wake_island(sleeper);
  }
  for (std::size_t j = 0; j < listed; ++j) {
    const std::uint32_t slot = jumped[j];
    if (slot < s.slot_.size() && s.slot_[slot] < n) jumped_flag[s.slot_[slot]] = 0;
    jumped_slot[slot] = 0;
  }
  jumped.erase(jumped.begin(), jumped.begin() + static_cast<std::ptrdiff_t>(listed));
}

// ---------------------------------------------------------------------------------------
// manifolds

void RigidContacts::update(RigidBodySystem& s, double dt) {
  Stopwatch clock;
  // last step's pairs hold the impulses the solver left; they are read as they are rewritten
  last_count = pairs.size();
  emitted = 0;
  preloaded.clear();
  pairs_same = true;  // until emit() finds an entry that differs
  const std::size_t n = s.type_.size();
  if (rotations.size() < n) rotations.resize(n), rotation_stamp.resize(n, 0), travel.resize(n);
  if (++stamp == 0) {
    std::fill(rotation_stamp.begin(), rotation_stamp.end(), 0);
    std::fill(shape_pose_stamp.begin(), shape_pose_stamp.end(), 0);
    stamp = 1;
  }
  update_proxies(s, dt);
  find_new_pairs(s);
  wake_touched(s);
  s.profile_.pairs = clock.seconds();
  s.profile_.moved = moved.size();
  clock.reset();
  make_manifolds(s);
  // last step's entries beyond this step's end: their impulses back to their manifolds
  for (std::size_t k = emitted; k < last_count; ++k)
    if (pairs[k].record != kNoIndex && manifolds[pairs[k].record].last == k) settle(pairs[k].record);
  pairs.resize(emitted);
  s.profile_.manifolds = clock.seconds();
}

namespace {

// How far (m) the points of a pair's cached manifold have moved against each other since the
// narrow phase made it: the centre's displacement plus the chord that the relative rotation
// turns the body's farthest point through (2 r sin(angle / 2)), measured in the frame of the
// body that holds the normal (b's when a dynamic body meets a static or kinematic one, else
// a's), so it bounds how much any point's separation along that normal has changed, and
// how much closer a point left out of the manifold has come. The centre alone is not enough:
// a body turning about its centre (a box rocking on the corner the four below it share, in
// Jolt's pyramid) moves its corners up to its reach times the angle, 3 cm at 1 degree for a
// 2 m cube, while its centre stays within the reuse distance.
// `in_b`: the normal is kept in b's frame; `reach` (m): the moving body's (extent_).
double carried_points_moved(bool in_b, double reach, const PairCache& c, const Vec3& rel_position,
                            const Quat& rel_rotation) {
  // sin(angle / 2) of the relative rotation since then, from its vector part (no cancellation)
  const Quat turn = glm::conjugate(c.rel_rotation) * rel_rotation;
  const double sin_half = std::sqrt(turn.x * turn.x + turn.y * turn.y + turn.z * turn.z);
  // the moving body's centre in the other's frame, then and now (a's in b's frame is -R^T p)
  const Vec3 shift = in_b ? glm::conjugate(c.rel_rotation) * c.rel_position - glm::conjugate(rel_rotation) * rel_position
                          : rel_position - c.rel_position;
  // (a shape of no finite reach, a plane or a mesh, moves infinitely far when it turns at all)
  return glm::length(shift) + (sin_half > 0 ? 2 * reach * sin_half : 0.0);
}

// Whether a touching pair's manifolds are carried over: its cache's margin still covers this
// step's, and its bodies' relative pose moved within the reuse thresholds since the cache's
// (the angle's cosine `cos_half`, the points' travel `reuse`, m). `rel_position`,
// `rel_rotation`: b's centre and frame in a's frame now, as the plan keeps them.
bool carried_over(const PairCache& c, double margin, double reuse, double cos_half, bool in_b, double reach,
                  const Vec3& rel_position, const Quat& rel_rotation) {
  return c.margin >= margin && std::abs(glm::dot(rel_rotation, c.rel_rotation)) >= cos_half &&
         carried_points_moved(in_b, reach, c, rel_position, rel_rotation) <= reuse;
}

// A ball's or a box's manifold with a plane (planes are on static bodies only), turned down by
// the general reuse test, carried when the narrow phase would make the same points now: a ball
// whose surface is within the reach of the plane (convex_plane's one point), a box whose corners
// within the reach are the manifold's (its feature ids, convex_plane's corner numbers; at most
// four, so none left out by reduce). A point 1e-9 (relative) or less from the reach either way
// is left to the narrow phase. A plane is flat, so a carried point's depth, which emit() makes
// between the plane's point and the body's core, is the body's point's depth now whatever the
// body moved; only the plane's point went stale (by the body's slide along the plane), and it is
// made again here under the body's core (the core projected onto the plane, in the plane's
// frame), where the narrow phase puts it. So the manifold is the narrow phase's to rounding, and
// its impulses those that collide_pair would match to it by id. On the rain's landing about
// 3,000 of the ground's ball manifolds and 2,700 box manifolds a step were made anew, nearly all
// because the body slid more than the reuse distance or turned more than the reuse angle.
// MOVES BITS against the rebuild: the points made by another arithmetic (their order too).
// (make_manifolds asks under_cores for a ball, box_on_plane for a box.) Their arguments:
// `plane_a`: the plane is a's shape (the normal, from a to b, then in a's frame, else in b's);
// `reach`: the narrow phase's (m); `rel_position`, `rel_rotation`: b's centre and frame in a's
// frame now; `lanes`: on the SIMD paths.

// The band about the reach within which a carried point's height is left to the narrow phase:
// 1e-9 of the magnitudes the height was made from (m): the plane's offset `off` (0 for a ball's,
// measured in the plane's frame), the height and the point `at` it was measured at
inline double carry_band(double off, double height, const Vec3& at) {
  return 1e-9 * (1 + std::abs(off) + std::abs(height) + std::abs(at.x) + std::abs(at.y) + std::abs(at.z));
}

// The plane's point under a body's core, a point a lane (a double, or the four of an AVX2
// vector), glm's operations in glm's order, so the same bits on every path: `c`, the body's
// core in its frame, becomes the plane's point in the plane's frame; returned, the core's
// distance along `n`: its height above the plane when the plane is a (the normal, from a to b,
// out of the plane), minus it when the plane is b (the normal into the plane): the callers
// take the sign. `p`, `q`: b's centre and frame in a's (q conjugated when the plane is b's);
// `o`, `n`: a point on the plane and its unit normal, in the plane's frame.
template <class V>
[[gnu::always_inline]] inline V under_core(bool plane_a, const V (&p)[3], const V (&q)[4], const V (&o)[3],
                                           const V (&n)[3], V (&c)[3]) {
  V x, y, z;
  if (plane_a) {
    // rel_position + rel_rotation * core
    detail::lanes::quat_turn(q[0], q[1], q[2], q[3], c[0], c[1], c[2], x, y, z);
    x = p[0] + x, y = p[1] + y, z = p[2] + z;
  } else {
    // conjugate(rel_rotation) * (core - rel_position)
    detail::lanes::quat_turn(q[0], q[1], q[2], q[3], c[0] - p[0], c[1] - p[1], c[2] - p[2], x, y, z);
  }
  // core - dot(core - o, n) n
  const V d = ((x - o[0]) * n[0] + (y - o[1]) * n[1]) + (z - o[2]) * n[2];
  c[0] = x - d * n[0], c[1] = y - d * n[1], c[2] = z - d * n[2];
  return d;
}

// The plane's points under the body's cores (under_core) into the manifold `r`, unless the body
// is a ball (`ball_radius` > 0, its one core its centre) that is no longer within `reach` (m) of
// the plane, as the narrow phase measures it, by more than its rounding: then false, and the
// manifold left as it was. On the SIMD paths a point a lane (the lanes past the count compute on
// what the rows hold there and are stored; nothing reads them), else a point at a time: the same
// bits.
#if PBA_EMIT_AVX2
__attribute__((target("avx2"))) bool under_cores_avx2(CachedManifold& r, bool plane_a, const Vec3& rel_position,
                                                      const Quat& rel_rotation, double ball_radius, double reach) {
  using V = __m256d;
  const double sign = plane_a ? 1.0 : -1.0;
  const Vec3 o = plane_a ? r.core_a(0) : r.core_b(0);
  const V p[3] = {_mm256_set1_pd(rel_position.x), _mm256_set1_pd(rel_position.y), _mm256_set1_pd(rel_position.z)};
  const V q[4] = {_mm256_set1_pd(sign * rel_rotation.x), _mm256_set1_pd(sign * rel_rotation.y),
                  _mm256_set1_pd(sign * rel_rotation.z), _mm256_set1_pd(rel_rotation.w)};
  const V ov[3] = {_mm256_set1_pd(o.x), _mm256_set1_pd(o.y), _mm256_set1_pd(o.z)};
  const V n[3] = {_mm256_set1_pd(r.normal.x), _mm256_set1_pd(r.normal.y), _mm256_set1_pd(r.normal.z)};
  const int from = plane_a ? 3 : 0, to = plane_a ? 0 : 3;
  V c[3] = {_mm256_loadu_pd(r.core[from]), _mm256_loadu_pd(r.core[from + 1]), _mm256_loadu_pd(r.core[from + 2])};
  const V d = under_core(plane_a, p, q, ov, n, c);
  if (ball_radius > 0) {
    const double height = sign * _mm256_cvtsd_f64(d);  // (the normal points into a plane that is b)
    if (!(height - ball_radius <= reach - carry_band(0, height, o))) return false;
  }
  for (int i = 0; i < 3; ++i) _mm256_storeu_pd(r.core[to + i], c[i]);
  return true;
}
#endif

bool under_cores(CachedManifold& r, bool plane_a, const Vec3& rel_position, const Quat& rel_rotation,
                 double ball_radius, double reach, bool lanes) {
#if PBA_EMIT_AVX2
  if (lanes) return under_cores_avx2(r, plane_a, rel_position, rel_rotation, ball_radius, reach);
#endif
  (void)lanes;
  const Quat q = plane_a ? rel_rotation : glm::conjugate(rel_rotation);
  const double pv[3] = {rel_position.x, rel_position.y, rel_position.z}, qv[4] = {q.x, q.y, q.z, q.w};
  const Vec3 o = plane_a ? r.core_a(0) : r.core_b(0);
  const double ov[3] = {o.x, o.y, o.z}, nv[3] = {r.normal.x, r.normal.y, r.normal.z};
  const int from = plane_a ? 3 : 0, to = plane_a ? 0 : 3;
  double c[Manifold::kMaxPoints][3];
  for (int k = 0; k < r.count; ++k) {
    for (int i = 0; i < 3; ++i) c[k][i] = r.core[from + i][k];
    const double height = (plane_a ? 1.0 : -1.0) * under_core(plane_a, pv, qv, ov, nv, c[k]);
    if (ball_radius > 0 && !(height - ball_radius <= reach - carry_band(0, height, o))) return false;
  }
  for (int k = 0; k < r.count; ++k)
    for (int i = 0; i < 3; ++i) r.core[to + i][k] = c[k][i];
  return true;
}

// The carry for a box: its corners within the reach, measured with the shapes at their
// poses as convex_plane measures them: the box's centre above the plane, plus each corner along
// the plane's normal in the box's frame (corner i: x, y, z of the signs of bits 1, 2, 4, as
// box_plane_corners numbers them); the heights' rounding against the narrow phase's is a few
// ulps of the coordinates. (A ball's is under_cores': its centre, its one core, within the reach
// of the plane, measured in the plane's frame as the plane's point is made again.) The plane in
// the world (`np`, `off`: plane_in_world) is made once a step for all the boxes on it.
struct WorldPlane {
  Vec3 np;     // the unit normal
  double off;  // the offset along it (m)
};
WorldPlane plane_in_world(const ColliderShape& plane, const Pose& plane_pose) {
  const Vec3 np = plane_pose.rotation * plane.normal;
  return {np, plane.offset + glm::dot(np, plane_pose.position)};
}

bool box_on_plane(CachedManifold& r, bool plane_a, const WorldPlane& plane, const ColliderShape& body,
                  const Pose& body_pose, double reach, const Vec3& rel_position, const Quat& rel_rotation, bool lanes) {
  const Vec3& np = plane.np;
  const double off = plane.off;
  const Vec3& at = body_pose.position;
  const double height = glm::dot(np, at) - off;
  const double tol = carry_band(off, height, at);
  const Vec3 u = glm::conjugate(body_pose.rotation) * np;
  const Vec3& h = body.half_extents;
  const double ux = h.x * u.x, uy = h.y * u.y, uz = h.z * u.z;
  unsigned within = 0;
  int count = 0;
  for (unsigned i = 0; i < 8; ++i) {
    const double d = height + ((i & 1) ? ux : -ux) + ((i & 2) ? uy : -uy) + ((i & 4) ? uz : -uz);
    if (d <= reach - tol) within |= 1u << i, ++count;
    else if (!(d > reach + tol)) return false;
  }
  if (count != r.count) return false;
  for (int k = 0; k < r.count; ++k) within &= ~(1u << r.id[k]);
  if (within != 0) return false;
  return under_cores(r, plane_a, rel_position, rel_rotation, 0, reach, lanes);
}

// The carry for a ball on a static mesh (the plane's for a ball, against one triangle's plane):
// its manifold is one point, and the narrow phase would make that triangle's face point alone
// (narrow::ball_on_face_alone: the ball over the triangle's interior within the reach of its
// plane, every other triangle near it beyond the reach); the triangle's point made again under
// the ball's centre, as for a plane (under_cores). On the terrain's settling steps (350-459)
// about 140 of the 220 ball pairs made anew a step had a manifold, nearly all turned down by
// the general test for the ball's roll (its turn moves the chord of its radius, not its centre)
// or its slide. `mesh_a`: the mesh is a's shape; `q_static`: the mesh's body's rotation (the
// frame of the manifold's normal); `radius`: the ball's (m); the rest as for under_cores.
bool ball_on_mesh(CachedManifold& r, bool mesh_a, const ColliderShape& mesh, const Pose& mesh_pose,
                  const Pose& ball_pose, const Quat& q_static, double radius, double reach, const MeshQueryCache& near,
                  const Vec3& rel_position, const Quat& rel_rotation, bool lanes) {
  // (the normal kept in the mesh's body's frame: meshes are static, so the ball is the pair's
  // moving body; said here so a moving mesh, if ever allowed, is declined, not misread)
  if (r.next != kNoIndex || r.count != 1 || r.normal_in_b == mesh_a) return false;
  // the normal and the ball's centre in the mesh's frame (the normal from the ball into the mesh)
  const Quat to_mesh = glm::conjugate(mesh_pose.rotation);
  const Vec3 n = to_mesh * (q_static * r.normal);
  const Vec3 centre = to_mesh * (ball_pose.position - mesh_pose.position);
  const auto largest = [](const Vec3& p) { return std::max(std::abs(p.x), std::max(std::abs(p.y), std::abs(p.z))); };
  const double world = std::max(largest(mesh_pose.position), largest(ball_pose.position));
  return narrow::ball_on_face_alone(*mesh.mesh, r.sub, centre, world, radius, reach, mesh_a ? -n : n, near) &&
         under_cores(r, mesh_a, rel_position, rel_rotation, radius, reach, lanes);
}

// A touching pair's reuse test in a lane (make_manifolds): the bodies (dense indices), its cache
// (or a blank one), this step's margin and reuse distance (m), and the reach of the body whose
// points move against the normal's (m).
struct ReuseLane {
  std::uint32_t a, b;
  const PairCache* cache;
  double margin, reuse, reach;
};

static_assert(offsetof(PairCache, rel_position) == 0 && offsetof(PairCache, rel_rotation) == 24 &&
                  offsetof(PairCache, margin) == 56 && sizeof(Quat) == 32 && offsetof(Quat, x) == 0 && offsetof(Quat, w) == 24,
              "reuse_lanes_avx2 loads a cache's relative pose and margin as two rows of four doubles, a quaternion as one");

#if PBA_EMIT_AVX2
// carried_over() for four lanes at once, in_b false (the normal in a's frame): the plan's
// relative pose (glm's conjugate, quaternion product and rotation of a vector) and the test,
// each lane the scalar code's operations in its order, so the same bits and the same outcome;
// `same` gets 1 or 0 a lane, and `rel` the relative pose a coordinate a row (rel_position's x,
// y, z, rel_rotation's x, y, z, w; rows of `stride`), for the pairs made anew and the test of
// those whose normal is in b's frame
__attribute__((target("avx2"))) void reuse_lanes_avx2(const ReuseLane* lane, const Quat* q, const Vec3* com,
                                                      double cos_half, std::uint8_t* same, double* rel,
                                                      std::size_t stride) {
  using V = __m256d;
  V qa[4], qb[4], ca[4], cb[4], cp[4], cr[4];  // (x, y, z, w) / (x, y, z, -) / the cache's
  columns4(_mm256_loadu_pd(&q[lane[0].a].x), _mm256_loadu_pd(&q[lane[1].a].x), _mm256_loadu_pd(&q[lane[2].a].x),
           _mm256_loadu_pd(&q[lane[3].a].x), qa);
  columns4(_mm256_loadu_pd(&q[lane[0].b].x), _mm256_loadu_pd(&q[lane[1].b].x), _mm256_loadu_pd(&q[lane[2].b].x),
           _mm256_loadu_pd(&q[lane[3].b].x), qb);
  columns4(row3(com[lane[0].a]), row3(com[lane[1].a]), row3(com[lane[2].a]), row3(com[lane[3].a]), ca);
  columns4(row3(com[lane[0].b]), row3(com[lane[1].b]), row3(com[lane[2].b]), row3(com[lane[3].b]), cb);
  {
    const double* c0 = &lane[0].cache->rel_position.x;
    const double* c1 = &lane[1].cache->rel_position.x;
    const double* c2 = &lane[2].cache->rel_position.x;
    const double* c3 = &lane[3].cache->rel_position.x;
    // (rel_position x y z, rel_rotation x) and (rel_rotation y z w, margin)
    columns4(_mm256_loadu_pd(c0), _mm256_loadu_pd(c1), _mm256_loadu_pd(c2), _mm256_loadu_pd(c3), cp);
    columns4(_mm256_loadu_pd(c0 + 4), _mm256_loadu_pd(c1 + 4), _mm256_loadu_pd(c2 + 4), _mm256_loadu_pd(c3 + 4), cr);
  }
  const V sign = _mm256_set1_pd(-0.0);
  const V c_rx = cp[3], c_ry = cr[0], c_rz = cr[1], c_rw = cr[2], c_margin = cr[3];
  const V margin = _mm256_set_pd(lane[3].margin, lane[2].margin, lane[1].margin, lane[0].margin);
  const V reuse = _mm256_set_pd(lane[3].reuse, lane[2].reuse, lane[1].reuse, lane[0].reuse);
  const V reach = _mm256_set_pd(lane[3].reach, lane[2].reach, lane[1].reach, lane[0].reach);
  // qa_inv = conjugate(q_a): (w, -x, -y, -z)
  const V iw = qa[3], ix = _mm256_xor_pd(qa[0], sign), iy = _mm256_xor_pd(qa[1], sign), iz = _mm256_xor_pd(qa[2], sign);
  // rel_position = qa_inv * (com_b - com_a), as glm turns a vector
  const V dx = cb[0] - ca[0], dy = cb[1] - ca[1], dz = cb[2] - ca[2];
  V px, py, pz;
  detail::lanes::quat_turn(ix, iy, iz, iw, dx, dy, dz, px, py, pz);
  const V two = _mm256_set1_pd(2.0);
  // rel_rotation = qa_inv * q_b (glm's product, p = qa_inv, q = q_b)
  const V bx = qb[0], by = qb[1], bz = qb[2], bw = qb[3];
  const V rw = iw * bw - ix * bx - iy * by - iz * bz;
  const V rx = iw * bx + ix * bw + iy * bz - iz * by;
  const V ry = iw * by + iy * bw + iz * bx - ix * bz;
  const V rz = iw * bz + iz * bw + ix * by - iy * bx;
  // |dot(rel_rotation, c.rel_rotation)|: (w w' + x x') + (y y' + z z')
  const V along = _mm256_andnot_pd(sign, (rw * c_rw + rx * c_rx) + (ry * c_ry + rz * c_rz));
  // carried_points_moved: turn = conjugate(c.rel_rotation) * rel_rotation (its vector part)
  const V jw = c_rw, jx = _mm256_xor_pd(c_rx, sign), jy = _mm256_xor_pd(c_ry, sign), jz = _mm256_xor_pd(c_rz, sign);
  const V tx = jw * rx + jx * rw + jy * rz - jz * ry;
  const V ty = jw * ry + jy * rw + jz * rx - jx * rz;
  const V tz = jw * rz + jz * rw + jx * ry - jy * rx;
  const V sin_half = _mm256_sqrt_pd(tx * tx + ty * ty + tz * tz);
  const V sx = px - cp[0], sy = py - cp[1], sz = pz - cp[2];
  const V length = _mm256_sqrt_pd(sx * sx + sy * sy + sz * sz);
  const V turned = _mm256_and_pd(_mm256_cmp_pd(sin_half, _mm256_setzero_pd(), _CMP_GT_OQ), two * reach * sin_half);
  const V moved = length + turned;
  const V ok = _mm256_and_pd(_mm256_and_pd(_mm256_cmp_pd(c_margin, margin, _CMP_GE_OQ),
                                           _mm256_cmp_pd(along, _mm256_set1_pd(cos_half), _CMP_GE_OQ)),
                             _mm256_cmp_pd(moved, reuse, _CMP_LE_OQ));
  const int bits = _mm256_movemask_pd(ok);
  for (int k = 0; k < 4; ++k) same[k] = static_cast<std::uint8_t>(bits >> k & 1);
  const V out[7] = {px, py, pz, rx, ry, rz, rw};
  for (int i = 0; i < 7; ++i) _mm256_storeu_pd(rel + i * stride, out[i]);
}
#endif

#if PBA_EMIT_AVX2
// collide_pair's turns of a new manifold into the bodies' frames: one point's three turns in
// three lanes; two to four points a point a lane, each body's turns in one go: each point's
// cores (a's surface point less radius_a along `n`, from a's centre, turned by conjugate(qa); b's
// plus radius_b, by conjugate(qb)) into r.core's rows, and the normal `n` turned by
// conjugate(q_ref) (qa's or qb's: `ref_b`) into r.normal, in a spare lane of that body's turn
// when there is one. Each lane makes glm's operations in glm's order (the vector sums left to
// right, quat_turn), so the same bits as the scalar code; the rows' lanes past `count` get
// point 0's cores or the normal's turn, which no one reads (emit reads the first `count`).
// (In glm's scalar code, with the conjugates, these turns were some 2.2 M of collide_pair's
// 6.8 M instructions a step of the rain's landing, about 7,500 manifolds with points; in
// lanes 1.5 M: docs/benchmarks.md, "The rain's built manifolds' turns in lanes".)
__attribute__((target("avx2"))) void keep_cores_avx2(const ContactPoint* points, int count, bool flip, const Vec3& n,
                                                     const Quat& qa, const Quat& qb, bool ref_b, const Vec3& com_a,
                                                     const Vec3& com_b, double radius_a, double radius_b,
                                                     CachedManifold& r) {
  using V = __m256d;
  auto on_a = [&](const ContactPoint* c) __attribute__((always_inline)) {
    return flip ? &c->point_b.x : &c->point_a.x;
  };
  auto on_b = [&](const ContactPoint* c) __attribute__((always_inline)) {
    return flip ? &c->point_a.x : &c->point_b.x;
  };
  if (count == 1) {
    // one point (most of the rain's and the terrain's manifolds): its three turns a lane each
    // (the normal, a's core, b's core; the fourth lane a's core again), the vectors made as
    // rows (x, y, z and a fourth double no lane's result depends on)
    V q[4], v[4], t[4];
    columns4(_mm256_loadu_pd(ref_b ? &qb.x : &qa.x), _mm256_loadu_pd(&qa.x), _mm256_loadu_pd(&qb.x),
             _mm256_loadu_pd(&qa.x), q);
    const V sign = _mm256_set1_pd(-0.0);
    const V nr = row3(n);
    const V va = (_mm256_loadu_pd(on_a(points)) - _mm256_set1_pd(radius_a) * nr) - row3(com_a);
    const V vb = (_mm256_loadu_pd(on_b(points)) + _mm256_set1_pd(radius_b) * nr) - row3(com_b);
    columns4(nr, va, vb, va, v);
    V rx, ry, rz;
    detail::lanes::quat_turn(_mm256_xor_pd(q[0], sign), _mm256_xor_pd(q[1], sign), _mm256_xor_pd(q[2], sign), q[3],
                             v[0], v[1], v[2], rx, ry, rz);
    columns4(rx, ry, rz, _mm256_setzero_pd(), t);
    _mm_storeu_pd(&r.normal.x, _mm256_castpd256_pd128(t[0]));
    _mm_store_sd(&r.normal.z, _mm256_extractf128_pd(t[0], 1));
    const __m128d alo = _mm256_castpd256_pd128(t[1]), blo = _mm256_castpd256_pd128(t[2]);
    _mm_store_sd(&r.core[0][0], alo), _mm_storeh_pd(&r.core[1][0], alo);
    _mm_store_sd(&r.core[2][0], _mm256_extractf128_pd(t[1], 1));
    _mm_store_sd(&r.core[3][0], blo), _mm_storeh_pd(&r.core[4][0], blo);
    _mm_store_sd(&r.core[5][0], _mm256_extractf128_pd(t[2], 1));
    return;
  }
  // two to four: a point a lane, a body's turn at a time; the points' rows (x, y, z, and a
  // fourth double no lane's result depends on), lanes past the count point 0's
  const ContactPoint* p1 = count > 1 ? &points[1] : &points[0];
  const ContactPoint* p2 = count > 2 ? &points[2] : &points[0];
  const ContactPoint* p3 = count > 3 ? &points[3] : &points[0];
  V pa[4], pb[4];
  columns4(_mm256_loadu_pd(on_a(points)), _mm256_loadu_pd(on_a(p1)), _mm256_loadu_pd(on_a(p2)),
           _mm256_loadu_pd(on_a(p3)), pa);
  columns4(_mm256_loadu_pd(on_b(points)), _mm256_loadu_pd(on_b(p1)), _mm256_loadu_pd(on_b(p2)),
           _mm256_loadu_pd(on_b(p3)), pb);
  const V nx = _mm256_set1_pd(n.x), ny = _mm256_set1_pd(n.y), nz = _mm256_set1_pd(n.z);
  const V ra = _mm256_set1_pd(radius_a), rb = _mm256_set1_pd(radius_b);
  // (p - radius n) - com and (p + radius n) - com, as glm's vector operations
  V ax = (pa[0] - ra * nx) - _mm256_set1_pd(com_a.x), ay = (pa[1] - ra * ny) - _mm256_set1_pd(com_a.y),
    az = (pa[2] - ra * nz) - _mm256_set1_pd(com_a.z);
  V bx = (pb[0] + rb * nx) - _mm256_set1_pd(com_b.x), by = (pb[1] + rb * ny) - _mm256_set1_pd(com_b.y),
    bz = (pb[2] + rb * nz) - _mm256_set1_pd(com_b.z);
  // the normal in lane 3 of its body's turn when the points leave it free
  const bool spare = count < 4;
  if (spare) {
    if (ref_b)
      bx = _mm256_blend_pd(bx, nx, 8), by = _mm256_blend_pd(by, ny, 8), bz = _mm256_blend_pd(bz, nz, 8);
    else
      ax = _mm256_blend_pd(ax, nx, 8), ay = _mm256_blend_pd(ay, ny, 8), az = _mm256_blend_pd(az, nz, 8);
  }
  // the conjugates' vector parts (glm::conjugate: -x, -y, -z; w as it is)
  V cx, cy, cz;
  detail::lanes::quat_turn(_mm256_set1_pd(-qa.x), _mm256_set1_pd(-qa.y), _mm256_set1_pd(-qa.z), _mm256_set1_pd(qa.w),
                           ax, ay, az, cx, cy, cz);
  _mm256_storeu_pd(r.core[0], cx), _mm256_storeu_pd(r.core[1], cy), _mm256_storeu_pd(r.core[2], cz);
  V dx, dy, dz;
  detail::lanes::quat_turn(_mm256_set1_pd(-qb.x), _mm256_set1_pd(-qb.y), _mm256_set1_pd(-qb.z), _mm256_set1_pd(qb.w),
                           bx, by, bz, dx, dy, dz);
  _mm256_storeu_pd(r.core[3], dx), _mm256_storeu_pd(r.core[4], dy), _mm256_storeu_pd(r.core[5], dz);
  if (spare) {
    r.normal = ref_b ? r.core_b(3) : r.core_a(3);
  } else {
    r.normal = glm::conjugate(ref_b ? qb : qa) * n;
  }
}
#endif

}  // namespace

void RigidContacts::make_manifolds(RigidBodySystem& s) {
  const ContactSettings& cs = s.settings_;
  const double cos_half = std::cos(0.5 * cs.reuse_angle);
  const bool reuse = cs.reuse_distance > 0;
  // whether some pair may take less than the settings' speculative or reuse distance (`thinnest`)
  const bool small_possible = kSpeculativePerHalfSize * thinnest < cs.speculative_distance ||
                              kReusePerHalfSize * thinnest < cs.reuse_distance;
  auto awake_dynamic = [&](std::uint32_t i) { return s.type_[i] == BodyType::Dynamic && !s.asleep_[i]; };
  // what becomes of a pair this step: kept as it is while its bodies sleep, ended when its fat
  // boxes part, without contact while its tight boxes are apart, else touching
  auto fate_of = [&](const ShapePair& p, std::uint32_t a, std::uint32_t b) {
    if (!awake_dynamic(a) && !awake_dynamic(b)) return PairPlan::Fate::Asleep;
    const ShapeProxy& pa = proxies[p.proxy_a];
    const ShapeProxy& pb = proxies[p.proxy_b];
    if (!pa.fat.overlaps(pb.fat)) return PairPlan::Fate::End;
    if (!pa.box.overlaps(pb.box)) return PairPlan::Fate::Apart;
    return PairPlan::Fate::Touching;
  };
  // The pairs go in spans of up to kSpan pairs holding up to kBoxes box-box pairs to make anew:
  // first each pair's plan (its fate and, touching, the margin, the relative pose, whether the
  // manifolds are carried over), and the span's box-box pairs that need the narrow phase made together
  // by collide_batch (several at a time in SIMD lanes; the same manifolds and caches to the bit
  // as collide() pair by pair); then the span's pairs in order as one loop would walk them.
  // (A span, not the whole list: its pairs' data is still in the cache when they are walked.)
  // A pair without a cache yet gets a fresh one when walked (new_cache), so its narrow cache
  // starts from NarrowPhaseCache{} in fresh_narrow until then.
  constexpr std::size_t kSpan = 64, kBoxes = 16;
  plans.resize(kSpan);
  fates.resize(kSpan);
  fresh_narrow.resize(kBoxes);
  box_manifolds.resize(kBoxes);
  const PairCache blank{};
  const BatchPath path = simd == SimdPath::Scalar ? BatchPath::Scalar : BatchPath::Best;
  std::size_t built = 0, reused = 0, keep = 0;
  // the pairs with a cache, and of them those whose cache does not follow the last one's in the pool
  std::size_t cached = 0, out_of_order = 0;
  std::uint32_t previous_cache = kNoIndex - 1;
  // the plane in the world that the last box's carry read, by its proxy (planes are on static
  // bodies: made once a step for all the boxes on it)
  std::uint32_t world_plane_proxy = kNoIndex;
  WorldPlane world_plane{};
  auto plane_of = [&](std::uint32_t proxy, const RigidShapeDef& plane, std::uint32_t body, std::uint32_t shape) {
    if (proxy != world_plane_proxy)
      world_plane = plane_in_world(plane.shape, shape_pose(s, proxy, body, shape)), world_plane_proxy = proxy;
    return world_plane;
  };
  // (no prefetch of the pairs ahead in the plan's loop: GCC 12 dropped the one written here
  // from 489d89a on, and forced inline it made the 2870 pyramid's manifold functions take 3-5%
  // more samples: docs/benchmarks.md, "A resting pile's reused manifolds")
  // the reuse tests' lanes (make_manifolds' scratch, on the stack): by touching pair of the
  // span, its inputs, its place in the span, whether the normal is b's, and the outcome (the
  // lanes padded to a multiple of four with the last pair's)
  std::array<ReuseLane, kSpan + 3> lanes;
  std::array<std::uint8_t, kSpan + 3> lane_same;
  std::array<std::uint8_t, kSpan> lane_pair, lane_in_b;
  // and on the SIMD paths their relative poses, a coordinate a row (reuse_lanes_avx2)
  constexpr std::size_t kRelStride = kSpan + 4;
  std::array<double, 7 * kRelStride> lane_rel;
  bool rel_made = false;
  // lane t's relative pose as reuse_lanes_avx2 left it
  auto lane_pose = [&](std::size_t t, Vec3& position, Quat& rotation) {
    const double* r = &lane_rel[t];
    position = Vec3(r[0], r[kRelStride], r[2 * kRelStride]);
    rotation = Quat(r[6 * kRelStride], r[3 * kRelStride], r[4 * kRelStride], r[5 * kRelStride]);
  };
  // lane t's reuse test on its relative pose (the plan's, or the lanes')
  auto carried = [&](std::size_t t, const Vec3& position, const Quat& rotation) {
    const ReuseLane& l = lanes[t];
    return carried_over(*l.cache, l.margin, l.reuse, cos_half, lane_in_b[t], l.reach, position, rotation);
  };
  for (std::size_t first = 0; first < shape_pairs.size();) {
    box_queries.clear();
    // the span's fates, and its touching pairs' margins and reuse distances into the lanes
    const std::size_t end = std::min(shape_pairs.size(), first + kSpan);
    std::size_t touching = 0;
    for (std::size_t k = first; k < end; ++k) {
      const ShapePair& p = shape_pairs[k];
      const std::uint32_t a = s.slot_[p.slot_a], b = s.slot_[p.slot_b];
      fates[k - first] = fate_of(p, a, b);
      if (fates[k - first] != PairPlan::Fate::Touching) continue;
      PairPlan& plan = plans[k - first];
      // points are made as far out as the two bodies can close in one step (speculative
      // contacts) (up to each body's size: faster ones are caught by the continuous pass)
      // (the setting's reach, or less for a small body: pair_speculative, with how far the
      // bodies' points travel by turning, up to each body's size)
      // (`small_possible`: whether any body may be that small); the manifolds are kept while
      // the pair's points move less than the reuse distance (less for a small body: pair_reuse)
      double reach = cs.speculative_distance;
      plan.reuse = cs.reuse_distance;
      if (small_possible) {
        const double thin = std::min(s.min_extent_[a], s.min_extent_[b]);
        if (kSpeculativePerHalfSize * thin < reach)
          reach = pair_speculative(cs, thin, turn_travel(s, a) + turn_travel(s, b));
        plan.reuse = pair_reuse(cs, thin);
      }
      plan.margin = reach + travel[a] + travel[b];
      const bool in_b = s.type_[a] == BodyType::Dynamic && s.type_[b] != BodyType::Dynamic;  // as collide_pair keeps it
      lanes[touching] = {a, b, p.cache == kNoIndex ? &blank : &caches[p.cache], plan.margin, plan.reuse,
                         in_b ? s.extent_[a] : s.extent_[b]};
      lane_pair[touching] = static_cast<std::uint8_t>(k - first), lane_in_b[touching] = in_b;
      ++touching;
    }
    // the reuse tests: b's centre and frame in a's frame against where they were when the
    // manifolds were made, four pairs at a time on the SIMD paths (the same bits; one pair at
    // a time, the plan's glm arithmetic was a third of the resting 2870 pyramid's
    // make_manifolds, some 170 instructions a pair: docs/benchmarks.md, "The reuse test in lanes")
    // (each pair's relative pose is made once: by the lanes, or here into its plan, for its
    // test and, made anew, its cache)
    rel_made = false;
#if PBA_EMIT_AVX2
    if (reuse && simd != SimdPath::Scalar && touching > 0) {
      for (std::size_t k = touching; k % 4 != 0; ++k) lanes[k] = lanes[touching - 1];
      for (std::size_t t = 0; t < touching; t += 4)
        reuse_lanes_avx2(&lanes[t], s.q_.data(), s.com_.data(), cos_half, &lane_same[t], &lane_rel[t], kRelStride);
      rel_made = true;
      // (the lanes hold the normal in a's frame; a dynamic body on a static or kinematic
      // one that comes first in the pair holds it in b's: tested again on the lanes' pose)
      for (std::size_t k = 0; k < touching; ++k) {
        if (!lane_in_b[k]) continue;
        Vec3 position;
        Quat rotation;
        lane_pose(k, position, rotation);
        lane_same[k] = carried(k, position, rotation);
      }
    }
#endif
    if (!rel_made) {
      for (std::size_t t = 0; t < touching; ++t) {
        PairPlan& plan = plans[lane_pair[t]];
        const ReuseLane& l = lanes[t];
        const Quat qa_inv = glm::conjugate(s.q_[l.a]);
        plan.rel_position = qa_inv * (s.com_[l.b] - s.com_[l.a]);
        plan.rel_rotation = qa_inv * s.q_[l.b];
        if (reuse) lane_same[t] = carried(t, plan.rel_position, plan.rel_rotation);
      }
    }
    // the pairs made anew: their relative pose for the cache (from the lanes), and the span's
    // box-box ones to the batch (the span ends at the kBoxes-th)
    std::size_t last = end;
    for (std::size_t t = 0; t < touching; ++t) {
      const std::size_t k = first + lane_pair[t];
      PairPlan& plan = plans[lane_pair[t]];
      plan.same = reuse && lane_same[t];
      plan.batched = kNoIndex;
      if (plan.same) continue;
      // a carried manifold's cache as collide_pair leaves it: the reuse test's pose and the
      // margin made for (the following steps reuse it, or not, as they would the narrow phase's)
      auto carry = [&](PairCache& c, double reach) {
        c.rel_position = plan.rel_position, c.rel_rotation = plan.rel_rotation, c.margin = reach;
        plan.same = true;
      };
      const ShapePair& p = shape_pairs[k];
      const std::uint32_t a = lanes[t].a, b = lanes[t].b;
      if (rel_made) lane_pose(t, plan.rel_position, plan.rel_rotation);
      // (the shapes' definitions read only on the paths that need them; their kinds are the pair's)
      auto shape_a = [&]() -> const RigidShapeDef& { return s.shapes_[a][p.shape_a]; };
      auto shape_b = [&]() -> const RigidShapeDef& { return s.shapes_[b][p.shape_b]; };
      // a ball or a box on a plane with its points: carried when the narrow phase would make
      // them again, the plane's points made again (the comment before under_core)
      if (reuse && p.cache != kNoIndex && (p.type_a == ShapeType::Plane || p.type_b == ShapeType::Plane) &&
          caches[p.cache].first != kNoIndex) {
        const bool plane_a = p.type_a == ShapeType::Plane;
        const RigidShapeDef& sa = shape_a();
        const RigidShapeDef& sb = shape_b();
        const ColliderShape& body = (plane_a ? sb : sa).shape;
        PairCache& c = caches[p.cache];
        CachedManifold& r = manifolds[c.first];
        const double reach = plan.margin + plan.reuse;
        const bool lanes_path = simd != SimdPath::Scalar;
        if (body.type == ShapeType::Sphere
                ? under_cores(r, plane_a, plan.rel_position, plan.rel_rotation, plane_a ? r.radius_b : r.radius_a, reach,
                              lanes_path)
                : body.type == ShapeType::Box &&
                      box_on_plane(r, plane_a, plane_of(plane_a ? p.proxy_a : p.proxy_b, plane_a ? sa : sb, plane_a ? a : b,
                                                        plane_a ? p.shape_a : p.shape_b),
                                   body, shape_pose(s, plane_a ? p.proxy_b : p.proxy_a, plane_a ? b : a,
                                                    plane_a ? p.shape_b : p.shape_a),
                                   reach, plan.rel_position, plan.rel_rotation, lanes_path)) {
          carry(c, reach);
          continue;
        }
      }
      // a ball on a mesh with one point: carried when the narrow phase would make it again
      // (the comment before ball_on_mesh)
      if (reuse && p.cache != kNoIndex && caches[p.cache].first != kNoIndex &&
          caches[p.cache].mesh_query != kNoIndex &&
          ((p.type_a == ShapeType::Mesh && p.type_b == ShapeType::Sphere) ||
           (p.type_b == ShapeType::Mesh && p.type_a == ShapeType::Sphere))) {
        const bool mesh_a = p.type_a == ShapeType::Mesh;
        PairCache& c = caches[p.cache];
        CachedManifold& r = manifolds[c.first];
        const double reach = plan.margin + plan.reuse;
        const Pose& pose_a = shape_pose(s, p.proxy_a, a, p.shape_a);
        const Pose& pose_b = shape_pose(s, p.proxy_b, b, p.shape_b);
        if (ball_on_mesh(r, mesh_a, (mesh_a ? shape_a() : shape_b()).shape, mesh_a ? pose_a : pose_b, mesh_a ? pose_b : pose_a,
                         s.q_[mesh_a ? a : b], mesh_a ? r.radius_b : r.radius_a, reach, mesh_queries[c.mesh_query],
                         plan.rel_position, plan.rel_rotation, simd != SimdPath::Scalar)) {
          carry(c, reach);
          continue;
        }
      }
      if (p.type_a != ShapeType::Box || p.type_b != ShapeType::Box) continue;
      plan.batched = static_cast<std::uint32_t>(box_queries.size());
      NarrowPhaseCache* narrow = &fresh_narrow[plan.batched];
      if (p.cache == kNoIndex) *narrow = NarrowPhaseCache{};
      else narrow = &caches[p.cache].narrow;
      box_queries.push_back({&shape_a().shape, shape_pose(s, p.proxy_a, a, p.shape_a), &shape_b().shape,
                             shape_pose(s, p.proxy_b, b, p.shape_b), plan.margin + plan.reuse, narrow});
      if (box_queries.size() == kBoxes) {
        last = k + 1;
        break;
      }
    }
    collide_batch(box_queries, {box_manifolds.data(), box_queries.size()}, ConvexMethod::Sat, path);

    // the span's pairs in order: ended, asleep or apart pairs as they are, touching ones
    // their manifolds (carried over, made above, or made now) to the solver
    for (std::size_t k = first; k < last; ++k) {
      if (k + kPairsAhead < last && fates[k + kPairsAhead - first] == PairPlan::Fate::Touching) {
        const ShapePair& pair_ahead = shape_pairs[k + kPairsAhead];
        const std::uint32_t ahead = pair_ahead.cache;
        // (its first cached manifold, what emit reads of it, here and not in the plan's loop,
        // where its lines crowded out the plan's own loads: in the rain's landing emit and
        // collide_pair took 25% fewer samples once it moved)
        if (ahead != kNoIndex && caches[ahead].first != kNoIndex)
          prefetch_lines<offsetof(CachedManifold, normal_impulse)>(&manifolds[caches[ahead].first]);
        // the bodies' rotation matrices, which emit turns the points by (the pair's first
        // load of them, 30% of emit's samples in the rain's landing), and the line of the
        // shapes' definitions that holds the materials collide_pair mixes (update() sized
        // `rotations` for every body), the latter only for a pair made anew: a carried-over
        // manifold holds its mixed material, and emit() reads the shapes only when the mix
        // rules changed; and the shapes' first lines (their kinds and sizes, which collide_pair
        // and the narrow phase read first: the plan no longer reads them, the pair's kinds
        // serving it)
        const std::uint32_t a = s.slot_[pair_ahead.slot_a], b = s.slot_[pair_ahead.slot_b];
        prefetch_lines<sizeof(Mat3)>(&rotations[a]), prefetch_lines<sizeof(Mat3)>(&rotations[b]);
        if (!plans[k + kPairsAhead - first].same) {
          const RigidShapeDef& sa = s.shapes_[a][pair_ahead.shape_a];
          const RigidShapeDef& sb = s.shapes_[b][pair_ahead.shape_b];
          __builtin_prefetch(&sa), __builtin_prefetch(&sa.material);
          __builtin_prefetch(&sb), __builtin_prefetch(&sb.material);
          // a mesh pair made anew: its triangles near the shape (collide_mesh's first load;
          // a sixth of its samples on the terrain waited on it)
          if (ahead != kNoIndex && caches[ahead].mesh_query != kNoIndex)
            prefetch_lines<sizeof(MeshQueryCache)>(&mesh_queries[caches[ahead].mesh_query]);
        }
      }
      // the pair in place, and moved down to `keep` only when an earlier one ended (a copy on
      // the stack, stored as two overlapping 16-byte halves and read back as two others, did
      // not forward from the store buffer: 17% of make_manifolds' samples on the resting 2870
      // pyramid sat right after that read)
      ShapePair& p = shape_pairs[k];
      auto keep_pair = [&] {
        if (keep != k) shape_pairs[keep] = p;
        ++keep;
      };
      if (p.cache != kNoIndex) out_of_order += p.cache != previous_cache + 1, previous_cache = p.cache, ++cached;
      const PairPlan::Fate fate = fates[k - first];
      // a pair whose bodies sleep (or sleep on a static body) is kept as it is, manifolds and
      // impulses, for when they wake; against a kinematic body that went away it ends
      if (fate == PairPlan::Fate::Asleep) {
        const std::uint32_t a = s.slot_[p.slot_a], b = s.slot_[p.slot_b];
        const bool kinematic = s.type_[a] == BodyType::Kinematic || s.type_[b] == BodyType::Kinematic;
        if (kinematic && !proxies[p.proxy_a].fat.overlaps(proxies[p.proxy_b].fat))
          free_pair(p);
        else
          keep_pair();
        continue;
      }
      // fat boxes apart: the pair ends
      if (fate == PairPlan::Fate::End) {
        free_pair(p);
        continue;
      }
      // tight boxes apart: no contact this step (the narrow-phase cache stays)
      if (fate == PairPlan::Fate::Apart) {
        if (p.cache != kNoIndex) free_manifolds(caches[p.cache]), caches[p.cache].margin = -1;
        keep_pair();
        continue;
      }
      const std::uint32_t a = s.slot_[p.slot_a], b = s.slot_[p.slot_b];
      const PairPlan& plan = plans[k - first];
      const bool fresh = p.cache == kNoIndex;
      if (fresh) p.cache = new_cache();
      keep_pair();
      PairCache& c = caches[p.cache];
      if (!plan.same) {
        if (plan.batched != kNoIndex && fresh) c.narrow = fresh_narrow[plan.batched];
        collide_pair(s, p, c, a, b, plan.margin + plan.reuse, plan.batched != kNoIndex ? &box_manifolds[plan.batched] : nullptr);
        c.rel_position = plan.rel_position, c.rel_rotation = plan.rel_rotation;
      }
      for (std::uint32_t m = caches[p.cache].first; m != kNoIndex; m = manifolds[m].next) {
        emit(s, p, m, a, b);
        ++(plan.same ? reused : built);
      }
    }
    first = last;
  }
  shape_pairs.resize(keep);
  // (a pass over the pool, done when an eighth of the pairs read it out of order)
  if (8 * out_of_order > cached) reorder_caches();
  s.profile_.built = built, s.profile_.reused = reused, s.profile_.shape_pairs = shape_pairs.size();
}

namespace {

// A ball pair's speculative point made where the balls touch (docs/rigid-bodies.md, "Oblique
// impacts of fast bodies"): centres ca, cb (m) moving at va, vb (m/s) over the step dt (s), radii
// ra, rb (m). A pair that closes and does not touch yet has its normal of the start of the step
// (the line of centres now) turned to the line of centres at the first t in [0, dt] where
// |d + v t| = ra + rb under the relative motion d + v t (the touch), or, when the line misses,
// at the closest approach in [0, dt]. Along it the speculative point's separation is
// (d + v t) . n - (ra + rb) - t v . n = -t v . n at the start of the step, so the solver's plane
// is reached at the touch exactly, and pushes along the line of centres there; along the normal
// of the closest approach the plane is not reached in the step at all. (The line of centres of
// the start, which the narrow phase gives, is first order in the step: a glancing impact pushed
// 3.6 degrees off at 60 Hz.) Exact for the relative linear motion; gravity the same on both
// bodies keeps it linear, a turning body's ball off its centre of mass is taken at its velocity
// now. Touching or parting pairs keep the narrow phase's normal.
void touch_normal(const Vec3& ca, const Vec3& va, const Vec3& cb, const Vec3& vb, double ra, double rb, double dt,
                  Manifold& m) {
  const Vec3 d = cb - ca, v = vb - va;
  const double r = ra + rb;
  const double closing = glm::dot(d, v);   // half of the quadratic's linear coefficient
  const double gap = glm::dot(d, d) - r * r;  // its constant
  if (!(closing < 0 && gap > 0)) return;
  const double vv = glm::dot(v, v);
  const double disc = closing * closing - vv * gap;
  // the first root (in the form without cancellation), else the closest approach
  double t = disc >= 0 ? gap / (std::sqrt(disc) - closing) : -closing / vv;
  t = std::min(t, dt);
  const Vec3 line = d + t * v;
  const double length = glm::length(line);
  if (!(length > 0)) return;
  const Vec3 n = line / length;
  m.normal = n;
  m.points[0].point_a = ca + ra * n;
  m.points[0].point_b = cb - rb * n;
  m.points[0].depth = r - glm::dot(d, n);
}

// a ball or a capsule: a segment (a point for a ball) swept by its radius
bool rounded(ShapeType t) { return t == ShapeType::Sphere || t == ShapeType::Capsule; }

// The segment of a ball's or a capsule's core at `pose` (m), p to q: a ball's centre at both ends,
// a capsule's axis (its local y, from -half_height to +half_height)
void core_segment(const ColliderShape& shape, const Pose& pose, Vec3& p, Vec3& q) {
  const Vec3 half = shape.type == ShapeType::Capsule ? pose.rotation * Vec3(0, shape.half_height, 0) : Vec3(0);
  p = pose.position - half, q = pose.position + half;
}

// touch_normal for a ball or a capsule against a capsule (docs/rigid-bodies.md, "Oblique impacts
// of fast bodies"): the cores are the segments a0-a1 and b0-b1 (m; a ball's a point) translating
// at va, vb (m/s) over the step dt (s), their radii ra, rb (m). Under the relative motion the
// cores' distance less ra + rb, f(t) = |closest points of a and (b + v t)| - (ra + rb), is convex
// in t (the distance of the point -v t from the convex set b - a) and its slope is v along the
// closest points' unit line. A pair that closes and does not touch yet takes the normal of the
// first root of f in [0, dt] (the touch), found by Newton's method from t = 0: on a convex f
// falling to a root Newton's steps climb monotonically and never pass it, so it ends at the
// touch or at dt (still closing) or where the slope turns (past the closest approach: the cores
// miss), where the closest approach is bisected on the slope's sign. The point's cores are the
// closest points there taken back to the start of the step (each a point of its body, which
// translates), so its separation along n is f(t) - t v . n, reached at the touch exactly, as
// the balls' (touch_normal), and along the normal of the closest approach never. On a capsule's
// side the normal is perpendicular to its axis. Exact for the relative translation; a turning
// capsule's axis is taken as it is now, its core at its centre's velocity now.
void touch_cores(const Vec3& a0, const Vec3& a1, const Vec3& va, const Vec3& b0, const Vec3& b1, const Vec3& vb,
                 double ra, double rb, double dt, Manifold& m) {
  const Vec3 v = vb - va;
  const double r = ra + rb;
  Vec3 qa, qb, line;
  double length = 0;
  // f at t, its slope into `slope`; the closest points (b's taken back by v t) into qa, qb
  const auto at = [&](double t, double& slope) {
    narrow::closest_segments(a0, a1, b0 + t * v, b1 + t * v, qa, qb);
    line = qb - qa, qb -= t * v;
    length = glm::length(line);
    slope = length > 0 ? glm::dot(line, v) / length : 0;
    return length - r;
  };
  double slope = 0, f = at(0, slope);
  if (!(slope < 0 && f > 0)) return;
  double t = 0, past = -1;  // (past: a t beyond the closest approach, if one was met)
  for (int k = 0; k < 40 && f > 1e-12 * r && t < dt; ++k) {
    const double next = std::min(t - f / slope, dt);
    if (!(next > t)) break;
    double rising = 0;
    const double g = at(next, rising);
    if (!(rising < 0)) {
      past = next;
      break;
    }
    t = next, f = g, slope = rising;
  }
  if (past >= 0)  // the cores miss: the closest approach between t (falling) and past (rising)
    for (int k = 0; k < 50; ++k) {
      const double mid = 0.5 * (t + past);
      double rising = 0;
      at(mid, rising);
      (rising < 0 ? t : past) = mid;
    }
  at(t, slope);
  if (!(length > 0)) return;
  const Vec3 n = line / length;
  m.normal = n;
  m.points[0].point_a = qa + ra * n;
  m.points[0].point_b = qb - rb * n;
  m.points[0].depth = r - glm::dot(qb - qa, n);
}

}  // namespace

// The narrow phase for one pair out to `reach` (m): its speculative margin plus its reuse
// distance (so the manifold stays good while the pair closes by that much; pair_reuse), into
// the pair's cache: each new point takes the impulse of the old point (of the same triangle)
// with the same feature id or, when the features changed (a face-on-face contact whose
// clipped corners sit on the edges flips their labels under jitter), of the nearest old
// point within the linear slop in a's frame (Jolt matches contact points by position the same way). Without that fallback a
// 5-box stack rocked at 0.04 rad/s. `made`: the pair's manifold when make_manifolds already
// made it (a box-box pair, by collide_batch, its narrow cache already updated), else null.
void RigidContacts::collide_pair(RigidBodySystem& s, const ShapePair& p, PairCache& c, std::uint32_t a,
                                 std::uint32_t b, double reach, const Manifold* made) {
  const ContactSettings& cs = s.settings_;
  const RigidShapeDef& sa = s.shapes_[a][p.shape_a];
  const RigidShapeDef& sb = s.shapes_[b][p.shape_b];
  const NarrowPhaseSettings ns{.speculative_margin = reach};
  const std::uint32_t old = c.first;
  // the shapes' core radii and mixed material (the same for every manifold of the pair): the old
  // manifold's when it has one mixed by the rules in force (they are the shapes', which do not
  // change while the pair lasts; emit mixes a manifold again when the rules change), else made
  double radius_a, radius_b, mixed_friction, mixed_restitution, mixed_rolling;
  if (old != kNoIndex && manifolds[old].friction_mix == cs.friction_mix &&
      manifolds[old].restitution_mix == cs.restitution_mix) {
    const CachedManifold& o = manifolds[old];
    radius_a = o.radius_a, radius_b = o.radius_b;
    mixed_friction = o.mixed_friction, mixed_restitution = o.mixed_restitution, mixed_rolling = o.mixed_rolling;
  } else {
    radius_a = core_radius(sa.shape), radius_b = core_radius(sb.shape);
    mixed_friction = mix(cs.friction_mix, sa.material.friction, sb.material.friction);
    mixed_restitution = mix(cs.restitution_mix, sa.material.restitution, sb.material.restitution);
    mixed_rolling =
        std::max(sa.rolling_resistance * rolling_radius(sa.shape), sb.rolling_resistance * rolling_radius(sb.shape));
  }
  // the normal is kept in the frame of the body that does not move, else in a's
  const bool in_b = s.type_[a] == BodyType::Dynamic && s.type_[b] != BodyType::Dynamic;
  // the turns into the bodies' frames in lanes on the SIMD paths (keep_cores_avx2), else by
  // glm's conjugates (made only there: made for every pair, they were 0.4 M instructions a
  // step of the rain's landing)
  const bool lanes = PBA_EMIT_AVX2 && simd != SimdPath::Scalar;
  const bool mesh_pair = sa.shape.type == ShapeType::Mesh || sb.shape.type == ShapeType::Mesh;
  // old points are matched within the pair's slop (less for a small body: pair_slop)
  const double slop = slop_of(s, a, b), slop2 = slop * slop;
  for (std::uint32_t o = old; o != kNoIndex; o = manifolds[o].next) settle(o);
  std::uint32_t tail = kNoIndex;
  c.first = kNoIndex;
  // one manifold (flipped when the mesh is a's shape) into the new chain
  // (inlined where it is called: as a call, its closure of some twenty references was stored
  // for every pair, 28 instructions a pair, and its locals went through memory; 0.98 M of the
  // rain's landing step's instructions)
  auto keep = [&](const Manifold& m, bool flip) __attribute__((always_inline)) {
    const std::uint32_t idx = new_manifold();
    CachedManifold& r = manifolds[idx];
    const Vec3 n = flip ? -m.normal : m.normal;
    r.next = kNoIndex;
    r.sub = m.sub_shape_b;
    r.count = m.count;
    r.normal_in_b = in_b;
    // (the turns in lanes on the SIMD paths: keep_cores_avx2, the same bits)
    bool turned = false;
#if PBA_EMIT_AVX2
    if (lanes) {
      keep_cores_avx2(m.points.data(), m.count, flip, n, s.q_[a], s.q_[b], in_b, s.com_[a], s.com_[b], radius_a,
                      radius_b, r);
      turned = true;
    }
#endif
    if (!turned) r.normal = glm::conjugate(in_b ? s.q_[b] : s.q_[a]) * n;
    r.radius_a = radius_a, r.radius_b = radius_b;
    r.friction_mix = cs.friction_mix, r.restitution_mix = cs.restitution_mix;
    r.mixed_friction = mixed_friction, r.mixed_restitution = mixed_restitution, r.mixed_rolling = mixed_rolling;
    // the old manifold, for its impulses: a convex pair's only one, or of a mesh pair the one
    // whose normal is closest to this one's (within the merge angle)
    // (the normals compared only for a mesh pair: a convex pair's old chain is one manifold)
    const CachedManifold* was = nullptr;
    double closest = kMergeCos;
    for (std::uint32_t o = old; o != kNoIndex; o = manifolds[o].next) {
      const CachedManifold& om = manifolds[o];
      if (!mesh_pair) {
        was = &om;
        continue;
      }
      const double along = glm::dot((om.normal_in_b ? s.q_[b] : s.q_[a]) * om.normal, n);
      if (along >= closest) was = &om, closest = along;
    }
    r.friction = was ? was->friction : Vec3(0);
    r.preload = was ? was->preload : 0.0f;
    r.twist = was ? was->twist : 0;
    r.rolling = was ? was->rolling : Vec3(0);
    for (int k = 0; k < m.count; ++k) {
      const ContactPoint& cp = m.points[k];
      if (!lanes) {
        const Vec3 core_a = glm::conjugate(s.q_[a]) * ((flip ? cp.point_b : cp.point_a) - radius_a * n - s.com_[a]);
        const Vec3 core_b = glm::conjugate(s.q_[b]) * ((flip ? cp.point_a : cp.point_b) + radius_b * n - s.com_[b]);
        for (int i = 0; i < 3; ++i) r.core[i][k] = core_a[i], r.core[3 + i][k] = core_b[i];
      }
      const Vec3 core_a = r.core_a(k);
      r.id[k] = cp.id;
      r.normal_impulse[k] = 0;
      if (!was) continue;
      int match = -1;
      for (int o = 0; o < was->count && match < 0; ++o)
        if (was->id[o] == cp.id) match = o;
      for (int o = 0; o < was->count && match < 0; ++o) {
        const Vec3 d = was->core_a(o) - core_a;
        if (glm::dot(d, d) <= slop2) match = o;
      }
      if (match >= 0) r.normal_impulse[k] = was->normal_impulse[match];
    }
    if (tail == kNoIndex)
      c.first = idx;
    else
      manifolds[tail].next = idx;
    tail = idx;
  };
  if (made) {
    if (made->count > 0) keep(*made, false);
  } else if (mesh_pair) {
    const Pose& pose_a = shape_pose(s, p.proxy_a, a, p.shape_a);
    const Pose& pose_b = shape_pose(s, p.proxy_b, b, p.shape_b);
    // a convex shape on a static mesh: a manifold per touching triangle, in the mesh tree's
    // order (the scratch grows until it holds them all)
    const bool mesh_a = sa.shape.type == ShapeType::Mesh;
    const ColliderShape& convex = mesh_a ? sb.shape : sa.shape;
    const ColliderShape& mesh = mesh_a ? sa.shape : sb.shape;
    if (mesh_scratch.empty()) mesh_scratch.resize(16);
    // the pair's triangles near the shape (a fresh cache from the pool the first time)
    if (c.mesh_query == kNoIndex) {
      if (free_mesh_queries.empty()) {
        c.mesh_query = static_cast<std::uint32_t>(mesh_queries.size());
        mesh_queries.emplace_back();
      } else {
        c.mesh_query = free_mesh_queries.back();
        free_mesh_queries.pop_back();
        mesh_queries[c.mesh_query] = MeshQueryCache{};
      }
    }
    MeshQueryCache* const near = &mesh_queries[c.mesh_query];
    int count = 0;
    for (;;) {
      // (the system's scalar path reaches the mesh's lanes too: the same bits, tested both ways)
      // (without collide_mesh's input checks, as collide_unchecked_into below: the shapes
      // were checked when their bodies were made, the poses are finite and unit, the reach finite)
      count = narrow::collide_mesh_unchecked(convex, mesh_a ? pose_b : pose_a, mesh, mesh_a ? pose_a : pose_b,
                                             mesh_scratch, ns, near,
                                             simd == SimdPath::Scalar ? BatchPath::Scalar : BatchPath::Best);
      if (count < static_cast<int>(mesh_scratch.size())) break;
      mesh_scratch.resize(2 * mesh_scratch.size());
    }
    // the triangles' manifolds of normals within 5 degrees of a group's first (in the tree's
    // order) become one along that normal, their points' depths measured along it, reduced
    // to four points as the narrow phase reduces a face's: a box on a flat mesh gets the
    // manifold it gets on a plane, whatever the triangles under it, and a body on a gently
    // curved mesh one manifold (Jolt merges a body pair's manifolds of nearly equal normals
    // the same way). Feature ids are per triangle, so the triangle is mixed into them
    group_of.resize(static_cast<std::size_t>(count));
    int groups = 0;
    for (int j = 0; j < count; ++j) {
      const Vec3& nj = mesh_scratch[static_cast<std::size_t>(j)].normal;
      int g = 0;
      while (g < groups) {
        const Vec3& ng = mesh_scratch[static_cast<std::size_t>(group_first[static_cast<std::size_t>(g)])].normal;
        if (glm::dot(ng, nj) >= kMergeCos) break;
        ++g;
      }
      if (g == groups) {
        if (group_first.size() <= static_cast<std::size_t>(groups)) group_first.resize(groups + 1);
        group_first[static_cast<std::size_t>(groups++)] = j;
      }
      group_of[static_cast<std::size_t>(j)] = g;
    }
    for (int g = 0; g < groups; ++g) {
      const Manifold& first = mesh_scratch[static_cast<std::size_t>(group_first[static_cast<std::size_t>(g)])];
      merge_scratch.clear();
      std::uint32_t deepest_triangle = first.sub_shape_b;
      double deepest = -INFINITY;
      for (int j = 0; j < count; ++j) {
        if (group_of[static_cast<std::size_t>(j)] != g) continue;
        const Manifold& m = mesh_scratch[static_cast<std::size_t>(j)];
        for (int k = 0; k < m.count; ++k) {
          const ContactPoint& cp = m.points[k];
          const double depth = glm::dot(cp.point_a - cp.point_b, first.normal);
          if (depth > deepest) deepest = depth, deepest_triangle = m.sub_shape_b;
          // a point that two triangles both give (a ball over their common edge, a box's
          // corner on it) is kept once, the deeper
          auto same = std::find_if(merge_scratch.begin(), merge_scratch.end(), [&](const narrow::Candidate& o) {
            const Vec3 d = o.b - cp.point_b;
            return glm::dot(d, d) <= kSamePoint * kSamePoint;
          });
          if (same == merge_scratch.end())
            merge_scratch.push_back({cp.point_a, cp.point_b, depth, cp.id ^ (m.sub_shape_b * 0x9e3779b1u)});
          else if (depth > same->depth)
            *same = {cp.point_a, cp.point_b, depth, cp.id ^ (m.sub_shape_b * 0x9e3779b1u)};
        }
      }
      // (into the convex pairs' scratch, not a Manifold zeroed a group: reduce writes the
      // normal, the count and the points keep reads)
      Manifold& merged = pair_manifold;
      narrow::reduce(merge_scratch.data(), static_cast<int>(merge_scratch.size()), first.normal, merged);
      merged.sub_shape_b = deepest_triangle;
      if (merged.count > 0) keep(merged, mesh_a);
    }
  } else {
    // (into the scratch, not zeroed first: keep reads only its first `count` points) (without
    // collide()'s input checks: the shapes were checked when their bodies were made, a plane's
    // normal unit; the shapes' frames within a float's range, by create's and set_pose's checks
    // of each (pose + turned local offset) and check_finite's after each step, their rotations
    // unit as body_pose and shape_frame normalise them; the reach is finite)
    narrow::collide_unchecked_into(sa.shape, shape_pose(s, p.proxy_a, a, p.shape_a), sb.shape,
                                   shape_pose(s, p.proxy_b, b, p.shape_b), ns, &c.narrow, pair_manifold);
    // two balls, or a ball or a capsule and a capsule, with one point: the normal of their touch
    // in this step (touch_normal, touch_cores)
    if (pair_manifold.count == 1 && rounded(sa.shape.type) && rounded(sb.shape.type)) {
      const Pose pose_a = shape_pose(s, p.proxy_a, a, p.shape_a), pose_b = shape_pose(s, p.proxy_b, b, p.shape_b);
      const Vec3 ca = pose_a.position, cb = pose_b.position;
      const Vec3 va = s.v_[a] + glm::cross(s.w_[a], ca - s.com_[a]), vb = s.v_[b] + glm::cross(s.w_[b], cb - s.com_[b]);
      if (sa.shape.type == ShapeType::Sphere && sb.shape.type == ShapeType::Sphere) {
        touch_normal(ca, va, cb, vb, sa.shape.radius, sb.shape.radius, s.last_dt_, pair_manifold);
      } else {
        Vec3 a0, a1, b0, b1;
        core_segment(sa.shape, pose_a, a0, a1), core_segment(sb.shape, pose_b, b0, b1);
        touch_cores(a0, a1, va, b0, b1, vb, sa.shape.radius, sb.shape.radius, s.last_dt_, pair_manifold);
      }
    }
    if (pair_manifold.count > 0) keep(pair_manifold, false);
  }
  // the old chain goes back to the pool
  PairCache old_chain;
  old_chain.first = old;
  free_manifolds(old_chain);
  c.margin = reach;
}

namespace {

// What emit() reads to put a cached manifold's points in the world at the bodies' poses now.
struct PointsInput {
  const double (*core)[Manifold::kMaxPoints];  // CachedManifold::core
  const std::uint32_t* id;                     // CachedManifold::id
  const Mat3* qa;                              // the bodies' rotations now
  const Mat3* qb;
  // their centres of mass now (m) and the normal in the world (referred to, not copied)
  const Vec3& com_a;
  const Vec3& com_b;
  const Vec3& n;
  double radius_a, radius_b;  // the shapes' core radii (m)
  double preload;     // the springs' shifted rest (m)
  int count;          // points, 1 to 4
};

// Point k of the manifold into the pair `out`: the cores at the poses now, the surface points
// on them, its midpoint (returned, m, in the world), its anchors from the centres, its overlap
// and its separation's offset from the cores, its feature id. One body for emit_points_scalar
// and emit_point_one, so the two cannot drift apart.
[[gnu::always_inline]] inline Vec3 emit_point(const PointsInput& in, int k, ContactPair& out) {
  const Vec3& n = in.n;
  SolverPoint& pt = out.points[k];
  // the cores now, the surface points on them, and the overlap between the surfaces
  const Vec3 sa = *in.qa * Vec3(in.core[0][k], in.core[1][k], in.core[2][k]);
  const Vec3 sb = *in.qb * Vec3(in.core[3][k], in.core[4][k], in.core[5][k]);
  const Vec3 core_a = in.com_a + sa, core_b = in.com_b + sb;
  const Vec3 on_a = core_a + in.radius_a * n, on_b = core_b - in.radius_b * n;
  const double depth = glm::dot(on_a - on_b, n);
  const Vec3 mid = 0.5 * (on_a + on_b);
  pt.at = mid, pt.sa = sa, pt.sb = sb;
  out.depth[k] = depth;
  // the separation now is -depth; keep it relative to the cores
  pt.offset = -depth - glm::dot(core_b - core_a, n) - in.preload;
  out.id[k] = in.id[k];
  return mid;
}

// The points (emit_point, one after another) into the pair `out`, their centroid (m, in the
// world) and their mean distance from it (m). The reference for emit_points_avx2.
[[gnu::always_inline]] inline void emit_points_scalar(const PointsInput& in, ContactPair& out, Vec3& centroid,
                                                       double& twist_radius) {
  Vec3 sum(0), at[Manifold::kMaxPoints];
  for (int k = 0; k < in.count; ++k) {
    at[k] = emit_point(in, k, out);
    sum += at[k];
  }
  sum /= static_cast<double>(in.count);
  centroid = sum;
  twist_radius = 0;
  for (int k = 0; k < in.count; ++k) twist_radius += glm::length(at[k] - sum);
  twist_radius /= in.count;
}

// emit_points_scalar for a manifold of one point (most of the terrain's and the rain's), the
// same operations in the same order on that point, without the loops, the points' copies and the
// centroid's and twist radius's divisions and square root: the centroid is 0 + the point (the
// scalar code's sum; divided by one it is itself) and the twist radius 0 (the point's distance
// from itself; for a point not finite the scalar code gives NaN, which nothing tells from 0: the
// twist acts, and its impulse is carried, only past a radius > 0, and one-point lanes do not
// read it)
[[gnu::always_inline]] inline void emit_point_one(const PointsInput& in, ContactPair& out, Vec3& centroid,
                                                   double& twist_radius) {
  centroid = Vec3(0) + emit_point(in, 0, out);
  twist_radius = 0;
}

static_assert(Manifold::kMaxPoints == 4 && sizeof(SolverPoint) == 80 && offsetof(SolverPoint, sa) == 24 &&
                  offsetof(SolverPoint, sb) == 48 && offsetof(SolverPoint, offset) == 72,
              "emit_points_avx2 writes a point as two rows of four doubles and one of two");

// emit_points_scalar's arithmetic with the four points in the lanes of AVX2 vectors (the cores
// loaded a coordinate at a time, CachedManifold::core): each lane does the same operations in
// the same order as the scalar code does for its point, and the centroid and the mean distance
// sum the points in their order, so both give the same bits. The lanes past the count compute
// on whatever the manifold holds there and are not summed; of them only the overlaps and ids
// are stored (nothing reads a pair's points past its count). The points go out as rows (the 4 x 4
// transposes of at, sa, sb and offset), their overlaps and ids as they are. (Inlined into its one
// caller, emit_frame_points_avx2.)
#if PBA_EMIT_AVX2
// 1 / count for the counts of two and four (a product by it is the quotient rounded once, the
// same bits; 0 and 1 never come here, 3 is divided)
constexpr double kInverseCount[Manifold::kMaxPoints + 1] = {0, 1, 0.5, 0, 0.25};

// x in every lane (a broadcast: `0 + x` would make a -0 +0)
[[gnu::always_inline]] __attribute__((target("avx2"))) inline __m256d all(const double& x) { return _mm256_broadcast_sd(&x); }

[[gnu::always_inline]] __attribute__((target("avx2"))) inline void emit_points_avx2(const PointsInput& in, ContactPair& out,
                                                                                 Vec3& centroid, double& twist_radius) {
  using V = __m256d;
  const double* qa = &(*in.qa)[0][0];  // glm's columns, one after another
  const double* qb = &(*in.qb)[0][0];
  V sa[3], sb[3], core_a[3], core_b[3], gap[3], mid[3];
  {
    const V ax = _mm256_loadu_pd(in.core[0]), ay = _mm256_loadu_pd(in.core[1]), az = _mm256_loadu_pd(in.core[2]);
    const V bx = _mm256_loadu_pd(in.core[3]), by = _mm256_loadu_pd(in.core[4]), bz = _mm256_loadu_pd(in.core[5]);
    for (int i = 0; i < 3; ++i) {
      // glm's mat3 * vec3: the columns times the vector's x, y, z, summed in that order
      sa[i] = all(qa[i]) * ax + all(qa[3 + i]) * ay + all(qa[6 + i]) * az;
      sb[i] = all(qb[i]) * bx + all(qb[3 + i]) * by + all(qb[6 + i]) * bz;
      core_a[i] = all(in.com_a[i]) + sa[i], core_b[i] = all(in.com_b[i]) + sb[i];
      const double ra = in.radius_a * in.n[i], rb = in.radius_b * in.n[i];
      const V on_a = core_a[i] + all(ra), on_b = core_b[i] - all(rb);
      gap[i] = on_a - on_b;
      mid[i] = all(0.5) * (on_a + on_b);
    }
  }
  const V n[3] = {all(in.n.x), all(in.n.y), all(in.n.z)};
  const V depth = gap[0] * n[0] + gap[1] * n[1] + gap[2] * n[2];
  const V apart = (core_b[0] - core_a[0]) * n[0] + (core_b[1] - core_a[1]) * n[1] + (core_b[2] - core_a[2]) * n[2];
  const V offset = -depth - apart - all(in.preload);
  // the overlaps and the ids of the points past the count too (the manifold's, which nothing
  // reads past it)
  _mm256_storeu_pd(out.depth, depth);
  std::memcpy(out.id, in.id, sizeof out.id);
  // the rows of the points: (at, sa.x), (sa.y, sa.z, sb.x, sb.y), (sb.z, offset; the rest of
  // the row is not stored)
  V rows[3][4] = {{mid[0], mid[1], mid[2], sa[0]}, {sa[1], sa[2], sb[0], sb[1]}, {sb[2], offset, depth, depth}};
  for (V(&r)[4] : rows) {
    const V t0 = _mm256_unpacklo_pd(r[0], r[1]), t1 = _mm256_unpackhi_pd(r[0], r[1]);
    const V t2 = _mm256_unpacklo_pd(r[2], r[3]), t3 = _mm256_unpackhi_pd(r[2], r[3]);
    r[0] = _mm256_permute2f128_pd(t0, t2, 0x20), r[1] = _mm256_permute2f128_pd(t1, t3, 0x20);
    r[2] = _mm256_permute2f128_pd(t0, t2, 0x31), r[3] = _mm256_permute2f128_pd(t1, t3, 0x31);
  }
  V sum = _mm256_setzero_pd();
  for (int k = 0; k < in.count; ++k) {
    double* to = reinterpret_cast<double*>(&out.points[k]);
    _mm256_storeu_pd(to, rows[0][k]), _mm256_storeu_pd(to + 4, rows[1][k]);
    _mm_storeu_pd(to + 8, _mm256_castpd256_pd128(rows[2][k]));
    sum = sum + rows[0][k];  // (its fourth lane, sa.x, is not read)
  }
  // (divided by 2 or 4 as multiplied by 0.5 or 0.25: the same bits, both the exact quotient
  // rounded once, without a division's latency in this chain; 3 divides)
  const double scale = kInverseCount[in.count];
  sum = in.count == 3 ? sum / _mm256_set1_pd(3.0) : sum * _mm256_set1_pd(scale);
  // (the centroid's coordinates broadcast and the distances summed by lane moves, not through
  // memory: this chain's latency ends every emit; the sum in point order, as the scalar loop's
  // 0 + d0 + d1 + ..., where 0 + d0 is d0, a square root being no -0 here)
  const V cx = _mm256_permute4x64_pd(sum, 0x00), cy = _mm256_permute4x64_pd(sum, 0x55);
  const V cz = _mm256_permute4x64_pd(sum, 0xaa);
  centroid = Vec3(_mm256_cvtsd_f64(cx), _mm256_cvtsd_f64(cy), _mm256_cvtsd_f64(cz));
  const V dx = mid[0] - cx, dy = mid[1] - cy, dz = mid[2] - cz;
  const V distance = _mm256_sqrt_pd(dx * dx + dy * dy + dz * dz);
  const __m128d low = _mm256_castpd256_pd128(distance), high = _mm256_extractf128_pd(distance, 1);
  double twist = _mm_cvtsd_f64(low) + _mm_cvtsd_f64(_mm_unpackhi_pd(low, low));
  if (in.count > 2) twist += _mm_cvtsd_f64(high);  // (count > 1: emit_frame_points_avx2 calls this for two to four points)
  if (in.count > 3) twist += _mm_cvtsd_f64(_mm_unpackhi_pd(high, high));
  twist_radius = in.count == 3 ? twist / 3.0 : twist * scale;
}

// three doubles of a Vec3, the fourth lane 0 (a masked load reads nothing past the vector)
[[gnu::always_inline]] __attribute__((target("avx2"))) inline __m256d load3(const Vec3& v) {
  return _mm256_maskload_pd(&v[0], _mm256_setr_epi64x(-1, -1, -1, 0));
}
// a matrix's columns (glm's, one after another), loaded as the halves and the last double that
// rotation() stores it as: a body's matrix is often made by the emit that reads it, and a load
// that spans two stores still in flight waits for both to leave (whole columns loaded at once,
// half of this function's samples on the terrain sat after the matrix's loads)
[[gnu::always_inline]] __attribute__((target("avx2"))) inline void columns(const Mat3& m, __m256d (&c)[3]) {
  const double* q = &m[0][0];
  const __m128d q01 = _mm_loadu_pd(q), q23 = _mm_loadu_pd(q + 2), q45 = _mm_loadu_pd(q + 4);
  const __m128d q67 = _mm_loadu_pd(q + 6), q8 = _mm_load_sd(q + 8);
  c[0] = _mm256_insertf128_pd(_mm256_castpd128_pd256(q01), q23, 1);                                // (q0, q1, q2, q3)
  c[1] = _mm256_permute4x64_pd(_mm256_insertf128_pd(_mm256_castpd128_pd256(q23), q45, 1), 0xf9);  // (q3, q4, q5, q5)
  c[2] = _mm256_insertf128_pd(_mm256_castpd128_pd256(q67), q8, 1);                                 // (q6, q7, q8, 0)
}
// (x + y) + z of the first three lanes, as glm's dot sums a product
[[gnu::always_inline]] __attribute__((target("avx2"))) inline __m128d sum3(__m256d v) {
  const __m128d low = _mm256_castpd256_pd128(v);
  return _mm_add_sd(_mm_add_sd(low, _mm_unpackhi_pd(low, low)), _mm256_extractf128_pd(v, 1));
}

static_assert(offsetof(ContactPair, twist_radius) == offsetof(ContactPair, ca) + sizeof(Vec3) &&
                  offsetof(SolverPoint, offset) == 9 * sizeof(double) && sizeof(Mat3) == 9 * sizeof(double),
              "emit_point_one_avx2 writes the anchor and twist radius as one row, a point as 4 + 4 + 4 + 1 doubles");

// emit_point_one in the lanes of one AVX2 vector (x, y, z and a fourth lane that is not kept):
// each lane does the scalar code's operations on its coordinate in the same order, and the dot
// products sum x, y, z in that order, so the same bits; the point's at, sa, sb and offset go out
// as three overlapping rows of four and one double, the anchor of friction (the centroid from
// a's centre) with the twist radius 0 as one row. A call (emit is built for SSE2) of about 83
// instructions, against about 130 of the scalar code's halves, broadcasts and spills inline.
__attribute__((target("avx2"))) void emit_point_one_avx2(const CachedManifold& r, const Mat3& qa, const Mat3& qb,
                                                         const Vec3& com_a, const Vec3& com_b, double nx, double ny,
                                                         double nz, ContactPair& out) {
  using V = __m256d;
  V ca[3], cb[3];
  columns(qa, ca), columns(qb, cb);
  // glm's mat3 * vec3: the columns times the vector's x, y, z, summed in that order
  const V sa = ca[0] * all(r.core[0][0]) + ca[1] * all(r.core[1][0]) + ca[2] * all(r.core[2][0]);
  const V sb = cb[0] * all(r.core[3][0]) + cb[1] * all(r.core[4][0]) + cb[2] * all(r.core[5][0]);
  const V n = _mm256_setr_pd(nx, ny, nz, 0);
  const V com_av = load3(com_a);
  const V core_a = com_av + sa, core_b = load3(com_b) + sb;
  const V on_a = core_a + all(r.radius_a) * n, on_b = core_b - all(r.radius_b) * n;
  const __m128d depth = sum3((on_a - on_b) * n);
  const __m128d apart = sum3((core_b - core_a) * n);
  const V mid = all(0.5) * (on_a + on_b);
  const double preload = r.preload;
  const __m128d offset = _mm_sub_sd(_mm_sub_sd(_mm_xor_pd(depth, _mm_set_sd(-0.0)), apart), _mm_set_sd(preload));
  // the rows: at (with sa.x after it), sa (with sb.x), sb (with offset), each written over the
  // last one's fourth lane, then the offset
  double* to = reinterpret_cast<double*>(&out.points[0]);
  _mm256_storeu_pd(to, mid), _mm256_storeu_pd(to + 3, sa), _mm256_storeu_pd(to + 6, sb);
  _mm_store_sd(to + 9, offset);
  _mm_store_sd(&out.depth[0], depth);
  out.id[0] = r.id[0];
  // the centroid 0 + the point (as the scalar sum) from a's centre, and after it the twist radius 0
  const V anchor = (_mm256_setzero_pd() + mid) - com_av;
  _mm256_storeu_pd(&out.ca[0], _mm256_blend_pd(anchor, _mm256_setzero_pd(), 0x8));
}

// emit's frame and points of a manifold of two to four points on the SIMD paths, in one call:
// the normal in the world (glm's mat3 * vec3 in the lanes of one vector, the columns times x,
// y, z summed in that order, as emit_point_one_avx2 turns a core), its tangents (tangent_basis),
// then emit_points_avx2 and the anchor of friction. The same bits as emit's scalar frame and
// the call of emit_points_avx2 it replaces; one call, not two with the points' input between
// them, so the tangents' division and the points' chain of sums, division and square roots
// that ends each emit (nearly half of emit_points_avx2's samples sat on it) are in flight together.
__attribute__((target("avx2"))) void emit_frame_points_avx2(const CachedManifold& r, const Mat3& qa, const Mat3& qb,
                                                            const Vec3& com_a, const Vec3& com_b, double preload,
                                                            ContactPair& out) {
  using V = __m256d;
  V m[3];
  columns(r.normal_in_b ? qb : qa, m);
  const V turned = m[0] * all(r.normal.x) + m[1] * all(r.normal.y) + m[2] * all(r.normal.z);
  const __m128d low = _mm256_castpd256_pd128(turned);
  const Vec3 n(_mm_cvtsd_f64(low), _mm_cvtsd_f64(_mm_unpackhi_pd(low, low)), _mm_cvtsd_f64(_mm256_extractf128_pd(turned, 1)));
  out.normal = n;
  tangent_basis(n, out.t1, out.t2);
  const PointsInput in{.core = r.core, .id = r.id, .qa = &qa, .qb = &qb, .com_a = com_a, .com_b = com_b, .n = n,
                       .radius_a = r.radius_a, .radius_b = r.radius_b, .preload = preload, .count = r.count};
  Vec3 centroid;
  double twist_radius;
  emit_points_avx2(in, out, centroid, twist_radius);
  out.ca = centroid - com_a;
  out.twist_radius = twist_radius;
}
#endif

}  // namespace

// One cached manifold to the solver: its points and normal in the world at the bodies' poses
// now (the separation of a point is measured between the shapes' cores, which ride with the
// bodies), the mixed material, and the impulses it carried (when warm starting).
void RigidContacts::emit(RigidBodySystem& s, const ShapePair& p, std::uint32_t record, std::uint32_t a,
                         std::uint32_t b) {
  const ContactSettings& cs = s.settings_;
  const CachedManifold& r = manifolds[record];
  // in place: last step's entries are overwritten (their impulses saved first when they are
  // another manifold's), new ones appended
  const std::size_t at_index = emitted++;
  if (at_index == pairs.size()) pairs.emplace_back();
  // last step's entry two distances ahead, which the next emits overwrite (read first: the
  // impulses); and of the entry a distance ahead, its record when it is another manifold's
  // (whenever the entries shifted: 58% of the terrain's emits), whose `last` is read before
  // the entry is overwritten (a load from the pool, its order not the pairs': 27% of emit's
  // samples on the terrain)
  if (at_index + 2 * kPairsAhead < last_count) prefetch_lines<sizeof(ContactPair)>(&pairs[at_index + 2 * kPairsAhead]);
  if (at_index + kPairsAhead < last_count) {
    const std::uint32_t displaced = pairs[at_index + kPairsAhead].record;
    if (displaced != kNoIndex) __builtin_prefetch(&manifolds[displaced].last);
  }
  ContactPair& c = pairs[at_index];
  CachedManifold& own = manifolds[record];
  const bool warm = cs.warm_starting;
  // the entry is the manifold's own of last step (a pile at rest): its impulses stay where they
  // are, and so does its key (its shape pair's, the triangle and the record: the entry was
  // written for this manifold, and a record freed and reused starts with no entry; a manifold
  // made anew is a new record, collide_pair)
  const bool in_place = own.last == at_index && c.record == record;
  const bool same_mix = own.friction_mix == cs.friction_mix && own.restitution_mix == cs.restitution_mix;
  // kept (a pile at rest): the entry holds last step's impulses, and the material, the count
  // and the entry's points count (pair_points) that this manifold wrote there last step (none
  // of them changes while it is carried over, and only emit writes them), so only what depends
  // on the poses is written
  const bool kept = warm && in_place && same_mix;
  // the colours' key of last step's entry here (color() keeps the colours while all match;
  // kept, the entry's rolling coefficient is this manifold's)
  pairs_same = pairs_same && at_index < last_count && c.a == a && c.b == b &&
               (kept || (c.rolling != 0) == (r.mixed_rolling != 0));
  Vec3 friction, rolling;
  double twist;
  if (kept) {
    friction = c.friction_impulse(), twist = c.twist_impulse, rolling = c.rolling_impulse;
  } else {
    if (c.record != record && c.record != kNoIndex && at_index < last_count && manifolds[c.record].last == at_index)
      settle(c.record);
    // this manifold's impulses: in this entry (the same place as last step), in another entry,
    // or saved in the cached manifold
    const ContactPair& from = own.last == kNoIndex ? c : pairs[own.last];
    const bool held = own.last != kNoIndex;
    // (all four, zeros past the count as store() leaves them: a loop of the count was a call of
    // memcpy, 1.3 M calls in the rain's first 200 steps; none in place and warm, where the entry
    // holds them already: their copy back was a call of memcpy, 0.7% of the resting 1240
    // pyramid's instructions) (`from` is another entry, or this one read point by point before
    // the point is written)
    if (!(warm && in_place))
      for (int k = 0; k < Manifold::kMaxPoints; ++k)
        c.normal_impulse[k] = warm && k < r.count ? (held ? from.normal_impulse[k] : r.normal_impulse[k]) : 0;
    friction = held ? from.friction_impulse() : r.friction;
    twist = held ? from.twist_impulse : r.twist;
    rolling = held ? from.rolling_impulse : r.rolling;
    if (held && own.last != at_index) pairs[own.last].record = kNoIndex;
    own.last = static_cast<std::uint32_t>(at_index);
    if (!in_place) {
      c.slot_a = p.slot_a, c.slot_b = p.slot_b, c.shape_a = p.shape_a, c.shape_b = p.shape_b, c.sub = r.sub;
      c.record = record;
    }
    // the material, mixed again if the rules changed since
    if (!same_mix) {
      const RigidShapeDef& sa = s.shapes_[a][p.shape_a];
      const RigidShapeDef& sb = s.shapes_[b][p.shape_b];
      own.friction_mix = cs.friction_mix, own.restitution_mix = cs.restitution_mix;
      own.mixed_friction = mix(cs.friction_mix, sa.material.friction, sb.material.friction);
      own.mixed_restitution = mix(cs.restitution_mix, sa.material.restitution, sb.material.restitution);
    }
    c.friction = r.mixed_friction;
    c.restitution = r.mixed_restitution;
    c.rolling = r.mixed_rolling;
    c.count = r.count;
    c.balls = rounded(p.type_a) && rounded(p.type_b) && r.count == 1 ? 1u : 0u;  // (the shapes' kinds)
    if (pair_points.size() <= at_index) pair_points.resize(pairs.capacity());  // (grows with the pairs)
    pair_points[at_index] = static_cast<std::uint8_t>(r.count);
  }
  c.a = a, c.b = b;
  const Mat3& qa = rotation(s, a);
  const Mat3& qb = rotation(s, b);
  const Vec3& com_a = s.com_[a];
  const Vec3& com_b = s.com_[b];
  // the springs' shifted rest (the soft step's; the other solvers drop it)
  if (r.preload != 0 && cs.solver != RigidSolverType::SoftStep) own.preload = 0;
  const double preload = r.preload;
  if (preload != 0) {
    if (preloaded.size() == preloaded.capacity()) preloaded.reserve(pairs.capacity() + 1);
    preloaded.push_back(static_cast<std::uint32_t>(at_index));
  }
  // the normal, its tangents and the points: more than one point on the SIMD paths four at a
  // time, with the frame, in one call (the same bits; the lanes cost what four points do, and
  // are dearer than scalar code only for one point: two in scalar code, a loop, the centroid's
  // sums, two square roots and two divisions, took about 325 instructions on the terrain, in the
  // lanes about 250 with the call); one alone without the centroid's machinery (in the lanes of
  // one AVX2 vector on the SIMD paths, which writes the anchor of friction and twist radius too)
  // (each value is computed into a local and stored from there: stored piecewise and read back
  // whole, a Vec3 waited on the store buffer)
#if PBA_EMIT_AVX2
  if (r.count > 1 && simd != SimdPath::Scalar) {
    emit_frame_points_avx2(r, qa, qb, com_a, com_b, preload, c);
  } else
#endif
  {
    const Vec3 n = (r.normal_in_b ? qb : qa) * r.normal;
    c.normal = n;
    tangent_basis(n, c.t1, c.t2);
    const double radius_a = r.radius_a, radius_b = r.radius_b;
#if PBA_EMIT_AVX2
    if (r.count == 1 && simd != SimdPath::Scalar) {
      emit_point_one_avx2(r, qa, qb, com_a, com_b, n.x, n.y, n.z, c);
    } else
#endif
    {
      // (made here: made for a call of emit_points_avx2 it was stored to the stack for every
      // manifold, the one-point ones too)
      const PointsInput in{.core = r.core, .id = r.id, .qa = &qa, .qb = &qb, .com_a = com_a, .com_b = com_b, .n = n,
                           .radius_a = radius_a, .radius_b = radius_b, .preload = preload, .count = r.count};
      Vec3 centroid;
      double twist_radius;
      if (r.count == 1)
        emit_point_one(in, c, centroid, twist_radius);
      else
        emit_points_scalar(in, c, centroid, twist_radius);
      c.ca = centroid - com_a;
      c.twist_radius = twist_radius;
    }
  }
  // friction carried over, re-projected onto this step's tangents
  c.tangent_impulse[0] = warm ? glm::dot(friction, c.t1) : 0;
  c.tangent_impulse[1] = warm ? glm::dot(friction, c.t2) : 0;
  // a constraint that does not act this step carries nothing (a carried twist impulse on a
  // one-point manifold, never clamped, spun a box on its corner up to 70 rad/s)
  c.twist_impulse = warm && c.twist_radius > 0 ? twist : 0;
  c.rolling_impulse = warm && c.rolling > 0 ? rolling : Vec3(0);
}

// ---------------------------------------------------------------------------------------
// bodies leaving

void RigidContacts::remove_body(RigidBodySystem& s, std::uint32_t slot, std::size_t i) {
  // its shapes leave the tree and the lists
  if (slot < body_proxies.size()) {
    for (const std::uint32_t q : body_proxies[slot]) {
      ShapeProxy& p = proxies[q];
      if (p.node >= 0) tree.destroy_proxy(p.node);
      std::erase(statics, q);
      std::erase(unbounded, q);
      p = ShapeProxy{};
      p.body = free_proxy;
      free_proxy = q;
    }
    body_proxies[slot].clear();
  }
  // its pairs, cached manifolds and contacts (the others' impulses saved first: the entries move)
  settle_all();
  std::size_t keep = 0;
  for (ShapePair& p : shape_pairs) {
    if (p.slot_a == slot || p.slot_b == slot)
      free_pair(p);
    else
      shape_pairs[keep++] = p;
  }
  shape_pairs.resize(keep);
  // (and their lanes with them, which manifold() reads until the next step; their colours are
  // made anew, the entries having moved; the columns measured anew)
  colored_once = false;
  column_known = false;
  std::size_t kept = 0;
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    if (pairs[k].slot_a == slot || pairs[k].slot_b == slot) continue;
    if (kept != k) {
      pairs[kept] = pairs[k];
      if (k < lane_of.size()) lane_of[kept] = lane_of[k];
      if (k < pair_points.size()) pair_points[kept] = pair_points[k];
    }
    ++kept;
  }
  pairs.resize(kept);
  if (lane_of.size() > kept) lane_of.resize(kept);
  emitted = pairs.size();
  // the body now at dense index i (the last one, moved into the hole) takes its proxies along
  if (i < s.type_.size() && s.owner_[i] < body_proxies.size())
    for (const std::uint32_t q : body_proxies[s.owner_[i]]) proxies[q].body = static_cast<std::uint32_t>(i);
  for (ContactPair& c : pairs) c.a = s.slot_[c.slot_a], c.b = s.slot_[c.slot_b];
}

}  // namespace pba::detail
