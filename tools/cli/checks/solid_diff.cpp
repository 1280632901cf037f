#include "checks/solid_diff.hpp"

#include <algorithm>
#include <cstdint>
#include <queue>
#include <unordered_map>

namespace tridex::cli {

namespace {

// The spans of one ray where exactly one of `a` and `b` holds material, longer than `tolerance`.
void solid_diff_ray(std::span<const DexelInterval> a, std::span<const DexelInterval> b,
                    DiffSpan base, double tolerance, std::vector<DiffSpan>& out) {
  if (a.size() == b.size() &&
      std::equal(a.begin(), a.end(), b.begin(), [](const DexelInterval& p, const DexelInterval& q) {
        return p.enter == q.enter && p.exit == q.exit;
      }))
    return;
  std::vector<float> cuts;
  for (const DexelInterval& i : a) cuts.push_back(i.enter), cuts.push_back(i.exit);
  for (const DexelInterval& i : b) cuts.push_back(i.enter), cuts.push_back(i.exit);
  std::sort(cuts.begin(), cuts.end());
  cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
  auto inside = [](std::span<const DexelInterval> s, float t) {
    for (const DexelInterval& i : s)
      if (i.enter <= t && t <= i.exit) return true;
    return false;
  };
  int state = 0, state_from = 0;  // 0 same, 1 removed, 2 left
  float from = 0;
  auto close = [&](float at) {
    if (state != 0 && at - from > tolerance) {
      DiffSpan s = base;
      s.from = from, s.to = at, s.removed = state == 1;
      out.push_back(s);
    }
  };
  for (std::size_t k = 0; k + 1 < cuts.size(); ++k) {
    const float mid = 0.5f * (cuts[k] + cuts[k + 1]);
    const bool in_a = inside(a, mid), in_b = inside(b, mid);
    state_from = in_a == in_b ? 0 : in_a ? 1 : 2;
    if (state_from != state) {
      close(cuts[k]);
      state = state_from, from = cuts[k];
    }
  }
  if (!cuts.empty()) close(cuts.back());
}

}  // namespace

std::vector<DiffSpan> solid_differences(const TripleDexel& a, const TripleDexel& b,
                                        double tolerance) {
  std::vector<DiffSpan> spans;
  for (int axis = 0; axis < 3; ++axis) {
    const DexelGrid& ga = a.grids[axis];
    const DexelGrid& gb = b.grids[axis];
    for (int iv = 0; iv < ga.nv; ++iv)
      for (int iu = 0; iu < ga.nu; ++iu)
        solid_diff_ray(ga.ray(iu, iv), gb.ray(iu, iv), DiffSpan{axis, iu, iv}, tolerance, spans);
  }
  return spans;
}

// Spans joined into regions through the lattice nodes they cover (26-neighbours, one kind).
std::vector<DiffRegion> connect_spans(const std::vector<DiffSpan>& spans, const TripleDexel& d) {
  const glm::ivec3 n = d.n;
  auto key = [&](glm::ivec3 c, bool removed) {
    return ((static_cast<std::uint64_t>(c.z) * static_cast<std::uint64_t>(n.y) +
             static_cast<std::uint64_t>(c.y)) *
                static_cast<std::uint64_t>(n.x) +
            static_cast<std::uint64_t>(c.x)) *
               2 +
           (removed ? 1u : 0u);
  };
  std::unordered_map<std::uint64_t, int> node_region;  // -1: not yet visited
  std::vector<std::pair<glm::ivec3, bool>> first_node(spans.size());
  for (std::size_t s = 0; s < spans.size(); ++s) {
    const DiffSpan& span = spans[s];
    const int a = span.axis;
    auto index = [&](double t) {
      return std::clamp(static_cast<int>(std::floor((t - d.origin[a]) / d.spacing + 0.5)), 0,
                        n[a] - 1);
    };
    int k0 = index(span.from), k1 = index(span.to);
    if (k1 < k0) k0 = k1 = index(0.5 * (span.from + span.to));
    glm::ivec3 c(0);
    c[TripleDexel::u_axis(a)] = span.iu;
    c[TripleDexel::v_axis(a)] = span.iv;
    for (int k = k0; k <= k1; ++k) {
      c[a] = k;
      node_region.emplace(key(c, span.removed), -1);
      if (k == k0) first_node[s] = {c, span.removed};
    }
  }
  // Breadth-first over the marked nodes.
  std::vector<DiffRegion> regions;
  for (std::size_t s = 0; s < spans.size(); ++s) {
    const auto [start, removed] = first_node[s];
    if (node_region.at(key(start, removed)) >= 0) continue;
    const int id = static_cast<int>(regions.size());
    DiffRegion region;
    region.removed = removed;
    regions.push_back(std::move(region));
    std::queue<glm::ivec3> queue;
    queue.push(start);
    node_region[key(start, removed)] = id;
    while (!queue.empty()) {
      const glm::ivec3 c = queue.front();
      queue.pop();
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const glm::ivec3 m = c + glm::ivec3(dx, dy, dz);
            if (glm::any(glm::lessThan(m, glm::ivec3(0))) || glm::any(glm::greaterThanEqual(m, n)))
              continue;
            auto it = node_region.find(key(m, removed));
            if (it == node_region.end() || it->second >= 0) continue;
            it->second = id;
            queue.push(m);
          }
    }
  }
  for (std::size_t s = 0; s < spans.size(); ++s) {
    const auto [start, removed] = first_node[s];
    regions[static_cast<std::size_t>(node_region.at(key(start, removed)))].spans.push_back(s);
  }
  return regions;
}

// Volume, deepest point, box and probes of each region; the regions largest first.
void measure_regions(std::vector<DiffRegion>& regions, const std::vector<DiffSpan>& spans,
                     const TripleDexel& d) {
  const double area = d.spacing * d.spacing;
  for (DiffRegion& region : regions) {
    double by_axis[3] = {0, 0, 0};
    std::vector<std::size_t> order = region.spans;
    for (std::size_t s : order) {
      const DiffSpan& span = spans[s];
      by_axis[span.axis] += (span.to - span.from) * area;
      region.box.extend(span.point(d, span.from));
      region.box.extend(span.point(d, span.to));
    }
    region.volume = std::max({by_axis[0], by_axis[1], by_axis[2]});
    std::sort(order.begin(), order.end(), [&](std::size_t p, std::size_t q) {
      return spans[p].to - spans[p].from > spans[q].to - spans[q].from;
    });
    const DiffSpan& deepest = spans[order.front()];
    region.depth = deepest.to - deepest.from;
    region.deepest = deepest.point(d, 0.5 * (deepest.from + deepest.to));
    for (std::size_t k = 0; k < order.size() && k < kDiffProbes; ++k) {
      const DiffSpan& span = spans[order[k]];
      region.probes.push_back(span.point(d, 0.5 * (span.from + span.to)));
    }
  }
  std::stable_sort(regions.begin(), regions.end(),
                   [](const DiffRegion& p, const DiffRegion& q) { return p.volume > q.volume; });
}

}  // namespace tridex::cli
