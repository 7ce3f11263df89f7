// Static triangle meshes: validation, normals, edge flags (no ghost contacts) and a
// bounding-volume hierarchy built by binned surface-area heuristic.
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "pba/collide/shape.h"

namespace pba {

namespace {

constexpr std::uint32_t kLeafSize = 4;   // triangles per leaf the builder aims for
constexpr int kMaxDepth = 60;            // query()'s stack holds 64 nodes
constexpr int kBins = 12;                // SAH bins per axis (Wald 2007)
// an internal edge bent by less than this sine is flat (float-rounded flat meshes stay flat)
constexpr double kFlatSine = 1e-4;

Aabb triangle_box(const Vec3& a, const Vec3& b, const Vec3& c) {
  return {glm::min(a, glm::min(b, c)), glm::max(a, glm::max(b, c))};
}

}  // namespace

/// Builds a TriangleMesh's normals, edge flags and BVH.
struct MeshBuilder {
  // the BVH over m.triangles_: binned SAH on centroids (Wald 2007, "On fast construction
  // of SAH-based bounding volume hierarchies"); children of a node are adjacent
  static void build_bvh(TriangleMesh& m) {
    const std::size_t nt = m.triangles_.size();
    std::vector<Aabb> boxes(nt);
    std::vector<Vec3> centers(nt);
    for (std::size_t t = 0; t < nt; ++t) {
      const auto& tr = m.triangles_[t];
      boxes[t] = triangle_box(m.vertices_[tr[0]], m.vertices_[tr[1]], m.vertices_[tr[2]]);
      centers[t] = boxes[t].center();
    }
    m.order_.resize(nt);
    for (std::uint32_t t = 0; t < nt; ++t) m.order_[t] = t;
    m.nodes_.reserve(2 * nt);
    std::vector<std::uint32_t> scratch(nt);
    m.nodes_.push_back({});
    struct Task {
      std::uint32_t node, begin, end;
      int depth;
    };
    std::vector<Task> tasks{{0, 0, static_cast<std::uint32_t>(nt), 0}};
    while (!tasks.empty()) {
      const Task task = tasks.back();
      tasks.pop_back();
      // bounds of the triangles and of their centres
      Aabb box = boxes[m.order_[task.begin]], cbox{centers[m.order_[task.begin]], centers[m.order_[task.begin]]};
      for (std::uint32_t i = task.begin; i < task.end; ++i) {
        box = box.merged(boxes[m.order_[i]]);
        cbox = cbox.merged({centers[m.order_[i]], centers[m.order_[i]]});
      }
      m.nodes_[task.node].box = box;
      const std::uint32_t count = task.end - task.begin;
      auto leaf = [&] {
        m.nodes_[task.node].first = task.begin;
        m.nodes_[task.node].count = count;
      };
      if (count <= kLeafSize || task.depth >= kMaxDepth) {
        leaf();
        continue;
      }
      // the cheapest bin boundary over the three axes
      int best_axis = -1, best_split = 0;
      double best_cost = static_cast<double>(count) * box.area();
      for (int axis = 0; axis < 3; ++axis) {
        const double lo = cbox.lo[axis], ext = cbox.hi[axis] - lo;
        if (!(ext > 0)) continue;
        std::array<std::uint32_t, kBins> n{};
        std::array<Aabb, kBins> bb{};
        for (std::uint32_t i = task.begin; i < task.end; ++i) {
          const std::uint32_t t = m.order_[i];
          const int b = std::min(kBins - 1, static_cast<int>(kBins * (centers[t][axis] - lo) / ext));
          bb[b] = n[b] ? bb[b].merged(boxes[t]) : boxes[t];
          ++n[b];
        }
        std::array<double, kBins> right_cost{};
        Aabb acc{};
        std::uint32_t cnt = 0;
        for (int b = kBins - 1; b > 0; --b) {
          if (n[b]) acc = cnt ? acc.merged(bb[b]) : bb[b], cnt += n[b];
          right_cost[b] = cnt ? cnt * acc.area() : 0;
        }
        acc = {};
        cnt = 0;
        for (int b = 0; b < kBins - 1; ++b) {
          if (n[b]) acc = cnt ? acc.merged(bb[b]) : bb[b], cnt += n[b];
          const double cost = (cnt ? cnt * acc.area() : 0) + right_cost[b + 1];
          if (cnt > 0 && cnt < count && cost < best_cost) best_cost = cost, best_axis = axis, best_split = b + 1;
        }
      }
      std::uint32_t mid;
      if (best_axis >= 0) {
        const double lo = cbox.lo[best_axis], ext = cbox.hi[best_axis] - lo;
        // a stable partition through the scratch array (left bins first, order kept)
        std::uint32_t nl = 0, nr = 0;
        for (std::uint32_t i = task.begin; i < task.end; ++i) {
          const std::uint32_t t = m.order_[i];
          const bool left = std::min(kBins - 1, static_cast<int>(kBins * (centers[t][best_axis] - lo) / ext)) < best_split;
          if (left) m.order_[task.begin + nl++] = t;
          else scratch[nr++] = t;
        }
        std::copy(scratch.begin(), scratch.begin() + nr, m.order_.begin() + task.begin + nl);
        mid = task.begin + nl;
      } else if (count <= 4 * kLeafSize) {
        leaf();  // splitting costs more than it saves
        continue;
      } else {
        // no useful bin split (coincident centres): halve by index along the widest axis
        const int axis = (cbox.hi - cbox.lo).x >= (cbox.hi - cbox.lo).y
                             ? ((cbox.hi - cbox.lo).x >= (cbox.hi - cbox.lo).z ? 0 : 2)
                             : ((cbox.hi - cbox.lo).y >= (cbox.hi - cbox.lo).z ? 1 : 2);
        mid = task.begin + count / 2;
        std::nth_element(m.order_.begin() + task.begin, m.order_.begin() + mid, m.order_.begin() + task.end,
                         [&](std::uint32_t a, std::uint32_t b) {
                           return std::tie(centers[a][axis], a) < std::tie(centers[b][axis], b);
                         });
      }
      // two adjacent children
      const std::uint32_t left = static_cast<std::uint32_t>(m.nodes_.size());
      m.nodes_[task.node].first = left;
      m.nodes_[task.node].count = 0;
      m.nodes_.push_back({});
      m.nodes_.push_back({});
      tasks.push_back({left + 1, mid, task.end, task.depth + 1});
      tasks.push_back({left, task.begin, mid, task.depth + 1});
    }
  }

  // the tree query() walks (TriangleMesh::QueryNode): nodes_'s inner nodes, root first, each
  // with its children's bounds rounded outwards to float, and each triangle's exact bounds in
  // the order of order_
  static void build_query_tree(TriangleMesh& m) {
    auto down = [](double x) {
      float f = static_cast<float>(x);
      return static_cast<double>(f) > x ? std::nextafter(f, -INFINITY) : f;
    };
    auto up = [](double x) {
      float f = static_cast<float>(x);
      return static_cast<double>(f) < x ? std::nextafter(f, INFINITY) : f;
    };
    m.query_nodes_.clear();
    m.order_boxes_.resize(m.order_.size());
    for (std::size_t i = 0; i < m.order_.size(); ++i) {
      const auto& tr = m.triangles_[m.order_[i]];
      m.order_boxes_[i] = triangle_box(m.vertices_[tr[0]], m.vertices_[tr[1]], m.vertices_[tr[2]]);
    }
    if (m.nodes_.empty() || m.nodes_[0].count > 0) return;
    // (node of nodes_, its QueryNode) to fill; an inner child gets the next QueryNode
    std::vector<std::pair<std::uint32_t, std::uint32_t>> todo{{0, 0}};
    m.query_nodes_.emplace_back();
    while (!todo.empty()) {
      const auto [node, q] = todo.back();
      todo.pop_back();
      for (std::uint32_t c = 0; c < 2; ++c) {
        const TriangleMesh::Node& child = m.nodes_[m.nodes_[node].first + c];
        TriangleMesh::QueryNode& qn = m.query_nodes_[q];
        for (int k = 0; k < 3; ++k) qn.lo[c][k] = down(child.box.lo[k]), qn.hi[c][k] = up(child.box.hi[k]);
        qn.count[c] = child.count;
        if (child.count > 0) {
          qn.first[c] = child.first;
        } else {
          qn.first[c] = static_cast<std::uint32_t>(m.query_nodes_.size());
          todo.push_back({m.nodes_[node].first + c, qn.first[c]});
          m.query_nodes_.emplace_back();  // (qn is not used past this point)
        }
      }
    }
  }

  // edge flags: set for boundary, non-manifold, inconsistently wound and convex edges
  static void build_edge_flags(TriangleMesh& m) {
    const std::size_t nt = m.triangles_.size();
    struct EdgeUse {
      std::uint64_t key;
      std::uint32_t tri, slot;
    };
    std::vector<EdgeUse> uses;
    uses.reserve(3 * nt);
    for (std::uint32_t t = 0; t < nt; ++t)
      for (std::uint32_t k = 0; k < 3; ++k) {
        const std::uint32_t a = m.triangles_[t][k], b = m.triangles_[t][(k + 1) % 3];
        uses.push_back({(std::uint64_t(std::min(a, b)) << 32) | std::max(a, b), t, k});
      }
    std::sort(uses.begin(), uses.end(),
              [](const EdgeUse& x, const EdgeUse& y) { return std::tie(x.key, x.tri, x.slot) < std::tie(y.key, y.tri, y.slot); });
    m.edge_flags_.assign(nt, 0);
    for (std::size_t i = 0; i < uses.size();) {
      std::size_t j = i;
      while (j < uses.size() && uses[j].key == uses[i].key) ++j;
      bool active = true;
      if (j - i == 2) {
        const EdgeUse &u = uses[i], &w = uses[i + 1];
        const auto &tu = m.triangles_[u.tri], &tw = m.triangles_[w.tri];
        // consistent winding runs the shared edge both ways
        if (tu[u.slot] == tw[(w.slot + 1) % 3]) {
          // convex when the far corner of one triangle lies below the other's plane
          const Vec3 a = m.vertices_[tu[u.slot]], b = m.vertices_[tu[(u.slot + 1) % 3]];
          const Vec3 far = m.vertices_[tw[(w.slot + 2) % 3]];
          const Vec3 e = glm::normalize(b - a);
          const Vec3 r = (far - a) - glm::dot(far - a, e) * e;  // across the edge, in w's plane
          const double s = glm::dot(m.normals_[u.tri], r) / glm::length(r);
          active = s < -kFlatSine;
        }
      }
      for (std::size_t k = i; k < j; ++k)
        if (active) m.edge_flags_[uses[k].tri] |= static_cast<std::uint8_t>(1u << uses[k].slot);
      i = j;
    }
  }
};

std::shared_ptr<const TriangleMesh> TriangleMesh::build(std::span<const Vec3> vertices,
                                                        std::span<const std::array<std::uint32_t, 3>> triangles,
                                                        std::string_view where) {
  // counts, finite vertices, indices in range, triangles with area
  if (triangles.empty()) throw Error(field_path(where, "triangles") + ": a mesh needs at least one triangle, got 0");
  require_count(static_cast<long long>(vertices.size()), 3, 1ll << 28, field_path(where, "vertices.size"));
  require_count(static_cast<long long>(triangles.size()), 1, 1ll << 28, field_path(where, "triangles.size"));
  // vertices finite and within a float's range (the colliders' range: beyond ~1e150 the
  // area test's products overflow)
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    if (fits_float(vertices[i])) continue;
    require_float(vertices[i], field_path(where, "vertices[" + std::to_string(i) + "]"));
  }
  auto m = std::make_shared<TriangleMesh>();
  m->vertices_.assign(vertices.begin(), vertices.end());
  m->triangles_.assign(triangles.begin(), triangles.end());
  m->normals_.resize(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const std::string at = field_path(where, "triangles[" + std::to_string(t) + "]");
    for (int k = 0; k < 3; ++k)
      if (triangles[t][k] >= vertices.size())
        throw Error(at + "[" + std::to_string(k) + "]: must be a vertex index in [0, " +
                    std::to_string(vertices.size() - 1) + "], got " + std::to_string(triangles[t][k]));
    const Vec3 a = vertices[triangles[t][0]], b = vertices[triangles[t][1]], c = vertices[triangles[t][2]];
    const Vec3 n = glm::cross(b - a, c - a);
    const double len = glm::length(n);
    // zero area: repeated or collinear corners (relative to the longest edge squared)
    const double l2 = std::max({glm::dot(b - a, b - a), glm::dot(c - b, c - b), glm::dot(a - c, a - c)});
    if (!(len > 1e-12 * l2))
      throw Error(at + ": degenerate triangle (zero area), vertices " + std::to_string(triangles[t][0]) + ", " +
                  std::to_string(triangles[t][1]) + ", " + std::to_string(triangles[t][2]));
    m->normals_[t] = n / len;
  }
  MeshBuilder::build_edge_flags(*m);
  MeshBuilder::build_bvh(*m);
  MeshBuilder::build_query_tree(*m);
  return m;
}

}  // namespace pba
