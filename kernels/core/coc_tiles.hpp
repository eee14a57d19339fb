#pragma once
// The tile-max circle-of-confusion map behind the gathers' adaptive mode (the FLAG paper's future
// work proposes "a max-downsampled CoC map ... with no impact on quality"). Everything is counted
// in disc indices (gather_pattern.hpp): a source whose radius has disc index m adds to the pixel at
// pattern offset (i k, j k) only if i^2 + j^2 <= m, so an integer says exactly which samples a disc
// covers. Per tile of tile_px x tile_px pixels:
//   M (max_index)   the largest disc index of its own pixels;
//   D (reach_index) the largest M of every tile whose discs can reach one of its pixels (itself
//                   included). Every sample that adds to a pixel of the tile then has
//                   i^2 + j^2 <= D, so a gather bounded by D adds exactly what the whole pattern
//                   adds, in the same order: the image is the same, bit for bit. D = 0: only each
//                   pixel's own sample reaches it, the tile's output is its input.
// Tile S reaches tile T if the nearest pixels of the two can be a pattern offset inside S's largest
// disc: with the pixel gaps gx, gy between them, gi = ceil(gx / k), gj = ceil(gy / k) must satisfy
// gi, gj <= n and gi^2 + gj^2 <= M_S. That is necessary for any sample of S to reach T, so D never
// misses a source (it may include a tile that cannot quite reach: a bound, never an error).
// shaders/common/tile_max.comp and tile_reach.comp compute the same integers on the GPU (tested equal).
// FLAG's own use of the map (the layers a tile's rows need) is in kernels/flag/flag_tiles.hpp.
#include <vector>

#include "gather_pattern.hpp"
#include "image.hpp"

namespace bokeh {

struct CocTiles {
  int tile_px = 16, tiles_x = 0, tiles_y = 0;
  std::vector<int> max_index;    // M, tiles_y x tiles_x, row-major
  std::vector<int> reach_index;  // D
  int scene_max_index = 0;       // the largest M: the scene's largest disc

  int tile_of(int x_px, int y_px) const { return (y_px / tile_px) * tiles_x + x_px / tile_px; }
  // The largest D over the tiles holding pixels [x0, x1] x [y0, y1] (inclusive, inside the image).
  int reach_over(int x0, int y0, int x1, int y1) const;
};

// How many tile rows or columns away a disc of the pattern can reach: ceil(n k / tile_px).
int tile_reach_range(const GatherPattern& pattern, int tile_px);
// Whether a tile whose largest disc index is m reaches a tile dtx, dty tiles away.
bool tile_reaches(int m, int dtx, int dty, int tile_px, const GatherPattern& pattern);

// M, D and the scene's largest index from the radii in channel 3 of `packed` (the CoC pass's output:
// rgb / area, radius px), with the pattern's disc indices (capped at 2 n^2; a NaN radius counts 0).
CocTiles coc_tiles(const Image& packed, const GatherPattern& pattern, int tile_px);

// ceil(gap / k): the samples between the nearest pixels of two tiles d tiles apart on one axis
// ((|d| - 1) tile_px + 1 px apart; 0 for d = 0).
int gap_samples(int d, int tile_px, int spacing_px);

}  // namespace bokeh
