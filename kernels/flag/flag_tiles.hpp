#pragma once
// FLAG's use of the tile-max CoC map (kernels/core/coc_tiles.hpp) in its adaptive mode: the layers a
// scene needs, and per tile Z, the highest layer any vertical pass reads from the tile's rows (-1:
// none), so the horizontal pass writes no layer nobody reads. shaders/flag/tile_layers.comp computes
// the same integers on the GPU (tested equal).
#include <vector>

#include "coc_tiles.hpp"
#include "gather_pattern.hpp"

namespace bokeh {

// FLAG's layer write bound Z per tile: the largest min(isqrt(D_T), n) over the tiles T of the same
// tile column with D_T > 0 whose vertical pass reaches the tile's rows (ceil(gap / k) <= that
// layer), -1 when there is none. n: the highest layer allocated.
std::vector<int> flag_write_layers(const CocTiles& tiles, int spacing_px, int half_n);

// The pattern FLAG needs for a scene whose largest disc index is m: n' = min(isqrt(m), n), i.e.
// n' + 1 layers. Its disc indices are capped at 2 n'^2 rather than 2 n^2; no source of the scene
// covers a sample the cap changes, so FLAG gives the same image with n' + 1 layers as with n + 1.
GatherPattern scene_sized_pattern(const GatherPattern& pattern, int scene_max_index);

}  // namespace bokeh
