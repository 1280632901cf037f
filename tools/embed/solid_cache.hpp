// tridex embedded — a session's solid kept up to date piece by piece (issue 38): Steps 2-3 of
// Inui, Chen and Umezu (CAD&A 19(4) 2022, §3.2) redone only where a piece's moves changed a Z-map.
//
// `tridex simulate` prepares each milled Z-map for the intersection (raise_uncut, then
// refine_steep_cells) and intersects the stock's triple dexel with all of them. Every stage is
// local: a prepared point depends on the milled and stock heights within two points of it, a
// steep cell on its four corners, a fine cell's sub-heights on the moves whose swept cutter
// reaches it (a minimum: the old sub-heights lowered by the new moves are the same as all moves'
// from the start), a ray of the result on the triangles of the polyhedra it crosses. So each
// direction keeps its prepared map and the fine cells' sub-heights before set_fine_cells; a piece
// marks the rows its moves reach; update() prepares those rows again, and the result's rays that
// cross their polyhedron's changed part (a box around those rows) are intersected again from the
// stock, every direction's map in turn, as scan_intersect_milled does. The rest are kept. The
// result is the same, bit for bit, as simulate's on the whole program (tests/embed).
//
// Two things are global, and when they change the direction is prepared whole and every ray
// redone: a new direction (a new polyhedron), and the highest prepared height (the fine cells'
// ceiling and the scan converter's fixed-point scale), which moves only when no point of a map is
// left uncut.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <vector>

#include "tridex/cutter.hpp"
#include "tridex/dexel.hpp"
#include "tridex/mesh.hpp"
#include "tridex/mill.hpp"
#include "tridex/zmap.hpp"

namespace tridex::embed {

class SolidCache {
 public:
  SolidCache() = default;
  // A box stock, or the closed mesh `stock_mesh` (its bounds `stock`) when not null.
  SolidCache(const Aabb& stock, std::shared_ptr<const Mesh> stock_mesh, const DexelLattice& lattice,
             unsigned threads);

  // `batch` was milled into direction g's live map `live` (a new direction when g is the count
  // so far): the rows its swept cutters reach are marked to be prepared again.
  void milled(std::size_t g, const ZMap& live, std::span<const Cutter> cutters,
              std::span<const CutMove> batch);

  // Brings the result up to date with the live maps and every direction's moves so far
  // (`cuts[g]`, frame-local tips), and returns it: W0 ∩ M1 ∩ … ∩ MN as simulate makes it.
  const TripleDexel& update(std::span<const ZMap> live, std::span<const Cutter> cutters,
                            std::span<const std::vector<CutMove>> cuts);

  const TripleDexel& stock_dexel() const { return stock_dexel_; }
  // The last update's share of rays intersected again (1 for a whole rebuild), for the tests.
  double last_rays_redone() const { return last_rays_redone_; }

 private:
  struct Direction {
    std::vector<std::uint32_t> raw_cells;  // its fine cells, ascending
    std::vector<float> raw_sub;            // their sub-heights before set_fine_cells
    float above = 0;                       // raise_uncut's height for uncut points
    float ceiling = 0;                     // the prepared map's highest point
    std::size_t moves_done = 0;            // moves of the direction already in `prepared`
    int row0 = std::numeric_limits<int>::max(), row1 = -1;  // point rows to prepare again
    bool whole = true;                                      // prepare every row
  };

  // Prepares point rows [r0, r1] of direction g's map again from its live map.
  void raise_rows(std::size_t g, const ZMap& live, int r0, int r1);
  // Finds the steep cells of cell rows [c0, c1] of direction g's prepared map and their
  // sub-heights (those fine before lowered by the new moves, the others by all `moves`).
  void refine_rows(std::size_t g, std::span<const Cutter> cutters, std::span<const CutMove> moves,
                   int c0, int c1);
  // Prepares direction g again (every row when d.whole); false when its ceiling moved.
  bool prepare(std::size_t g, const ZMap& live, std::span<const Cutter> cutters,
               std::span<const CutMove> moves);
  // Marks the rays of every family that cross the world box of `box`, local to `frame`.
  void mark_rays(const Frame& frame, const Aabb& box);
  // Intersects the marked rays again from the stock, every direction in turn.
  void redo_marked_rays();

  Aabb stock_;
  std::shared_ptr<const Mesh> stock_mesh_;
  unsigned threads_ = 0;
  TripleDexel stock_dexel_;
  TripleDexel result_;
  bool result_valid_ = false;
  std::vector<Direction> directions_;
  std::vector<ZMap> prepared_;  // per direction: raised and refined, as simulate intersects them
  std::vector<std::uint8_t> redo_[3];  // rays of each family to intersect again
  double last_rays_redone_ = 0;
};

}  // namespace tridex::embed
