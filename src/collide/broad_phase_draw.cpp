// Debug drawing of the broad phase: the tree's nodes by depth, the grid's occupied cells,
// and the proxies' boxes, through pba::DebugDraw (no graphics here).
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "pba/collide/broad_phase.h"

namespace pba {

void draw_box_edges(DebugDraw& dd, const Aabb& b, Color c) {
  const Vec3& l = b.lo;
  const Vec3& h = b.hi;
  // four edges along each axis
  for (int i = 0; i < 4; ++i) {
    const double u = (i & 1) ? h.y : l.y, v = (i & 2) ? h.z : l.z;
    dd.line({l.x, u, v}, {h.x, u, v}, c);
    const double s = (i & 1) ? h.x : l.x, t = (i & 2) ? h.z : l.z;
    dd.line({s, l.y, t}, {s, h.y, t}, c);
    const double p = (i & 1) ? h.x : l.x, q = (i & 2) ? h.y : l.y;
    dd.line({p, q, l.z}, {p, q, h.z}, c);
  }
}

void draw_broad_phase(const BroadPhase& bp, DebugDraw& dd, const DrawFlags& flags, int max_depth) {
  if (flags.tree && bp.method() == BroadPhaseMethod::Tree) {
    // the inner nodes, depth by depth, from warm (root) to cool (deep)
    const DynamicTree& t = bp.tree();
    const auto nodes = t.nodes();
    if (t.root() != DynamicTree::kNull) {
      struct Item {
        std::int32_t node;
        int depth;
      };
      std::vector<Item> stack{{t.root(), 0}};
      while (!stack.empty()) {
        const Item it = stack.back();
        stack.pop_back();
        const DynamicTree::Node& n = nodes[static_cast<std::size_t>(it.node)];
        if (n.is_leaf() || it.depth > max_depth) continue;
        const float f = max_depth > 0 ? float(it.depth) / float(max_depth) : 0.0f;
        draw_box_edges(dd, n.box, Color::rgb(1.0f - 0.8f * f, 0.45f + 0.35f * f, 0.2f + 0.75f * f, 0.8f));
        stack.push_back({n.child1, it.depth + 1});
        stack.push_back({n.child2, it.depth + 1});
      }
    }
  } else if (flags.tree && bp.method() == BroadPhaseMethod::Grid && bp.stats().grid_cell > 0) {
    // the occupied cells, each once
    const double h = bp.stats().grid_cell;
    std::vector<std::array<std::int64_t, 3>> cells;
    for (std::uint32_t p = 0; p < bp.slots() && cells.size() < 200000; ++p) {
      const ProxyId id = bp.id_at(p);
      if (id.is_null()) continue;
      const Aabb& b = bp.box(id);
      const Vec3 c0 = glm::floor(b.lo / h), c1 = glm::floor(b.hi / h);
      if ((c1.x - c0.x + 1) * (c1.y - c0.y + 1) * (c1.z - c0.z + 1) > 64) continue;
      for (double x = c0.x; x <= c1.x; ++x)
        for (double y = c0.y; y <= c1.y; ++y)
          for (double z = c0.z; z <= c1.z; ++z)
            cells.push_back({std::int64_t(x), std::int64_t(y), std::int64_t(z)});
    }
    std::sort(cells.begin(), cells.end());
    cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
    for (const auto& c : cells) {
      const Vec3 lo = Vec3(double(c[0]), double(c[1]), double(c[2])) * h;
      draw_box_edges(dd, {lo, lo + Vec3(h)}, Color::hex(0x00a2c7, 0.5f));
    }
  }
  if (flags.aabbs) {
    for (std::uint32_t p = 0; p < bp.slots(); ++p) {
      const ProxyId id = bp.id_at(p);
      if (id.is_null()) continue;
      draw_box_edges(dd, bp.box(id), Color::hex(0xffc53d, 0.6f));
    }
  }
}

}  // namespace pba
