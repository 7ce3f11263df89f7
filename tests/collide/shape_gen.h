// Test helper: point clouds and meshes for the shape tests (icosphere, box corners).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "pba/core.h"

namespace pba::test_support {

/// An icosphere of radius r: the icosahedron subdivided `level` times, vertices on the sphere.
/// Triangles are counter-clockwise from outside.
struct IcoSphere {
  std::vector<Vec3> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};
inline IcoSphere icosphere(int level, double r = 1) {
  IcoSphere s;
  const double t = (1 + std::sqrt(5.0)) / 2;
  s.vertices = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  s.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (Vec3& v : s.vertices) v = glm::normalize(v);
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      s.vertices.push_back(glm::normalize(s.vertices[a] + s.vertices[b]));
      const auto id = static_cast<std::uint32_t>(s.vertices.size() - 1);
      mid.emplace(key, id);
      return id;
    };
    std::vector<std::array<std::uint32_t, 3>> next;
    for (const auto& tr : s.triangles) {
      const std::uint32_t a = midpoint(tr[0], tr[1]), b = midpoint(tr[1], tr[2]), c = midpoint(tr[2], tr[0]);
      next.push_back({tr[0], a, c});
      next.push_back({tr[1], b, a});
      next.push_back({tr[2], c, b});
      next.push_back({a, b, c});
    }
    s.triangles = std::move(next);
  }
  for (Vec3& v : s.vertices) v *= r;
  return s;
}

/// A terrain: an n x n grid of cells over [-size/2, size/2]^2 in x-z, height h(x, z), two
/// triangles per cell wound so their normals point up (+y).
template <class H>
IcoSphere terrain(int n, double size, H height) {
  IcoSphere m;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) {
      const double x = size * (double(i) / n - 0.5), z = size * (double(j) / n - 0.5);
      m.vertices.push_back(Vec3(x, height(x, z), z));
    }
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(i * (n + 1) + j); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      m.triangles.push_back({id(i, j), id(i, j + 1), id(i + 1, j)});
      m.triangles.push_back({id(i + 1, j), id(i, j + 1), id(i + 1, j + 1)});
    }
  return m;
}

/// The 12 outward-wound triangles of the box |x| <= h.
inline IcoSphere box_mesh(const Vec3& h) {
  IcoSphere m;
  for (int i = 0; i < 8; ++i) m.vertices.push_back(Vec3(i & 1 ? h.x : -h.x, i & 2 ? h.y : -h.y, i & 4 ? h.z : -h.z));
  const std::uint32_t quads[6][4] = {{1, 3, 7, 5}, {0, 4, 6, 2}, {2, 6, 7, 3}, {0, 1, 5, 4}, {4, 5, 7, 6}, {0, 2, 3, 1}};
  for (const auto& q : quads) {
    m.triangles.push_back({q[0], q[1], q[2]});
    m.triangles.push_back({q[0], q[2], q[3]});
  }
  return m;
}

}  // namespace pba::test_support
