#include "pipeline/reach.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <unordered_map>
#include <utility>

#include "tridex/error.hpp"
#include "tridex/parallel.hpp"

namespace tridex::cli {

std::vector<Aabb> local_paths(const std::vector<gcode::MoveGroup>& groups, unsigned threads) {
  std::vector<Aabb> paths(groups.size());
  constexpr std::size_t kChunk = std::size_t{1} << 16;
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const gcode::MoveGroup& group = groups[g];
    const std::size_t n = group.moves.size(), chunks = (n + kChunk - 1) / kChunk;
    std::vector<Aabb> part(chunks);
    detail::for_each_chunk(chunks, threads, [&](std::size_t c) {
      for (std::size_t k = c * kChunk; k < std::min(n, (c + 1) * kChunk); ++k) {
        const gcode::Move m = group.moves[k];
        part[c].extend(group.frame.to_local(m.start)), part[c].extend(group.frame.to_local(m.end));
      }
    });
    for (const Aabb& box : part) paths[g].extend(box);
  }
  return paths;
}

std::optional<Aabb> reach_of_moves(const std::vector<gcode::MoveGroup>& groups,
                                   std::span<const Aabb> paths,
                                   const std::vector<gcode::Move>& simultaneous,
                                   std::span<const Cutter> cutters,
                                   const std::map<int, std::uint32_t>& cutter_of_tool,
                                   const Aabb& stock) {
  if (!simultaneous.empty()) return std::nullopt;
  Aabb reach;
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const gcode::MoveGroup& group = groups[g];
    double radius = 0;
    for (int tool : group.tools)
      if (const auto found = cutter_of_tool.find(tool); found != cutter_of_tool.end())
        radius = std::max(radius, cutters[found->second].radius());
    const Aabb& path = paths[g];
    if (path.empty()) continue;
    // Everything above the cutter is removed: the prism goes up to the stock's top.
    const double top = local_bounds(group.frame, stock).max.z;
    if (path.min.z > top) continue;
    const Vec3 lo(path.min.x - radius, path.min.y - radius, path.min.z);
    const Vec3 hi(path.max.x + radius, path.max.y + radius, top);
    for (int k = 0; k < 8; ++k)
      reach.extend(group.frame.to_world(
          Vec3((k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z)));
  }
  if (reach.empty()) return std::nullopt;
  const Aabb clipped{glm::max(reach.min, stock.min), glm::min(reach.max, stock.max)};
  if (clipped.empty()) return std::nullopt;
  return clipped;
}

std::optional<Aabb> clipped_reach(const Aabb& reach, const Aabb& stock, double spacing) {
  const double margin = kReachMarginCells * spacing;
  Aabb r{glm::max(reach.min - Vec3(margin), stock.min),
         glm::min(reach.max + Vec3(margin), stock.max)};
  if (r.empty()) return std::nullopt;
  int touching = 0;
  std::array<int, 3> touched{};  // -1: the min face, 1: the max face, 0: neither
  for (int a = 0; a < 3; ++a)
    for (const bool high : {false, true}) {
      const double gap = high ? stock.max[a] - r.max[a] : r.min[a] - stock.min[a];
      if (gap <= 0)
        ++touching, touched[static_cast<std::size_t>(a)] = high ? 1 : -1;
      else if (gap < margin)
        return std::nullopt;  // nearly touching: a sliver of a frame
    }
  const Vec3 size = r.size(), whole = stock.size();
  const double longest = std::max({size.x, size.y, size.z});
  if (touching != 1 || longest > 0.25 * std::max({whole.x, whole.y, whole.z})) return std::nullopt;
  // Each side a whole number of cells and a half, grown inside the stock: covering() centres
  // the nodes, so none lies on a face (a face on a layer of nodes came out 1e-4 mm off the
  // stock's, and the frame around it tilted by as much).
  for (int a = 0; a < 3; ++a) {
    const double extra = (std::ceil(size[a] / spacing - 0.5) + 0.5) * spacing - size[a];
    const int t = touched[static_cast<std::size_t>(a)];
    if (t <= 0) r.max[a] += t < 0 ? extra : 0.5 * extra;
    if (t >= 0) r.min[a] -= t > 0 ? extra : 0.5 * extra;
  }
  return r;
}

namespace {

// The face of `stock` that `reach` touches: (axis, 1 for the max side).
std::pair<int, int> touched_face(const Aabb& reach, const Aabb& stock) {
  for (int a = 0; a < 3; ++a) {
    if (reach.min[a] <= stock.min[a]) return {a, 0};
    if (reach.max[a] >= stock.max[a]) return {a, 1};
  }
  detail::fail("stitching the reach box: it touches no face of the stock");
}

// Appends triangle (a, b, c) turned to face `normal`.
void add_facing(Mesh& mesh, std::uint32_t a, std::uint32_t b, std::uint32_t c, const Vec3& normal) {
  const Vec3 pa(mesh.positions[a]), pb(mesh.positions[b]), pc(mesh.positions[c]);
  if (glm::dot(glm::cross(pb - pa, pc - pa), normal) < 0) std::swap(b, c);
  mesh.triangles.emplace_back(a, b, c);
}

// M's triangles less those on R's faces inside the stock, and the rim they leave, in order.
std::vector<std::uint32_t> drop_inner_faces(const Mesh& clipped, const Aabb& reach, int axis,
                                            int side, double eps, Mesh& out) {
  auto on_face = [&](const glm::vec3& p, int b, int s) {
    return std::abs(double(p[b]) - (s ? reach.max[b] : reach.min[b])) <= eps;
  };
  out.positions = clipped.positions;
  for (const glm::uvec3& t : clipped.triangles) {
    bool inner = false;
    for (int b = 0; b < 3 && !inner; ++b)
      for (int s = 0; s < 2 && !inner; ++s)
        inner = !(b == axis && s == side) && on_face(clipped.positions[t.x], b, s) &&
                on_face(clipped.positions[t.y], b, s) && on_face(clipped.positions[t.z], b, s);
    if (!inner) out.triangles.push_back(t);
  }
  std::set<std::pair<std::uint32_t, std::uint32_t>> edges;
  for (const glm::uvec3& t : out.triangles)
    edges.insert({t.x, t.y}), edges.insert({t.y, t.z}), edges.insert({t.z, t.x});
  std::unordered_map<std::uint32_t, std::uint32_t> next;
  for (const auto& [a, b] : edges)
    if (!edges.count({b, a}) && !next.emplace(a, b).second)
      detail::fail("stitching the reach box: the rim touches itself");
  if (next.size() < 4) detail::fail("stitching the reach box: no rim on the stock's face");
  std::vector<std::uint32_t> rim{next.begin()->first};
  while (rim.size() <= next.size()) {
    const auto found = next.find(rim.back());
    if (found == next.end()) detail::fail("stitching the reach box: the rim is open");
    if (found->second == rim.front()) break;
    rim.push_back(found->second);
  }
  if (rim.size() != next.size()) detail::fail("stitching the reach box: the rim is not one loop");
  for (std::uint32_t v : rim)
    if (!on_face(clipped.positions[v], axis, side))
      detail::fail("stitching the reach box: a cut reaches its faces inside the stock");
  return rim;
}

}  // namespace

Mesh stitch_into_stock(const Mesh& clipped, const Aabb& reach, const Aabb& stock, double spacing) {
  const auto [axis, side] = touched_face(reach, stock);
  const double eps = 0.01 * spacing;
  Mesh out;
  const std::vector<std::uint32_t> rim = drop_inner_faces(clipped, reach, axis, side, eps, out);
  // The stock's corners: corner k has the max of axis a where bit a of k is set.
  const auto base = static_cast<std::uint32_t>(out.positions.size());
  for (int k = 0; k < 8; ++k)
    out.positions.emplace_back(glm::vec3((k & 1) ? stock.max.x : stock.min.x,
                                         (k & 2) ? stock.max.y : stock.min.y,
                                         (k & 4) ? stock.max.z : stock.min.z));
  auto corner = [&](int a, int sa, int b, int sb, int c, int sc) {
    return base + static_cast<std::uint32_t>((sa << a) | (sb << b) | (sc << c));
  };
  // The five faces R does not touch: two triangles each.
  for (int b = 0; b < 3; ++b)
    for (int s = 0; s < 2; ++s) {
      if (b == axis && s == side) continue;
      const int u = (b + 1) % 3, v = (b + 2) % 3;
      Vec3 normal(0);
      normal[b] = s ? 1 : -1;
      add_facing(out, corner(b, s, u, 0, v, 0), corner(b, s, u, 1, v, 0), corner(b, s, u, 1, v, 1),
                 normal);
      add_facing(out, corner(b, s, u, 0, v, 0), corner(b, s, u, 1, v, 1), corner(b, s, u, 0, v, 1),
                 normal);
    }
  // The touched face less R's rectangle: for each corner of the rectangle, the rim's vertex
  // nearest to it; between two of them the rim runs along one side, fanned from the stock's
  // corner on the first one's quadrant.
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  std::vector<std::pair<std::size_t, int>> connectors;  // (index on the rim, quadrant iu + 2 iv)
  for (int q = 0; q < 4; ++q) {
    const double cu = (q & 1) ? reach.max[u] : reach.min[u];
    const double cv = (q & 2) ? reach.max[v] : reach.min[v];
    std::size_t best = 0;
    double nearest = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < rim.size(); ++k) {
      const glm::vec3& p = out.positions[rim[k]];
      const double d = std::hypot(double(p[u]) - cu, double(p[v]) - cv);
      if (d < nearest) nearest = d, best = k;
    }
    connectors.emplace_back(best, q);
  }
  std::sort(connectors.begin(), connectors.end());
  for (std::size_t k = 1; k < 4; ++k)
    if (connectors[k].first == connectors[k - 1].first)
      detail::fail("stitching the reach box: its rim has too few vertices");
  Vec3 normal(0);
  normal[axis] = side ? 1 : -1;
  for (std::size_t k = 0; k < 4; ++k) {
    const auto [from, q_from] = connectors[k];
    const auto [to, q_to] = connectors[(k + 1) % 4];
    const std::uint32_t o_from = corner(axis, side, u, q_from & 1, v, (q_from >> 1) & 1);
    const std::uint32_t o_to = corner(axis, side, u, q_to & 1, v, (q_to >> 1) & 1);
    for (std::size_t i = from; i != to; i = (i + 1) % rim.size())
      add_facing(out, o_from, rim[i], rim[(i + 1) % rim.size()], normal);
    add_facing(out, o_from, rim[to], o_to, normal);
  }
  return out;
}

}  // namespace tridex::cli
