// Radius-following circular filter: the tiles each bucket's passes visit (tiles.comp), shared by
// layers.comp, tiles.comp, plan.comp and the convolution passes.
// TileState (uints): [0, 4 * 32) the lists' counts, list (f, k, pass) at 2 (32 f + k - 1) + pass
// (pass 0 horizontal, 1 vertical; f 0 far, 1 near; k 1..31); then the raw per-tile bucket masks of
// both fields (layers.comp, atomicOr), then the row-dilated masks (tiles.comp STEP 0). The counts
// and raw masks are zeroed every frame. TileLists: list l holds up to `tiles` entries from l * tiles.
// Needs no Params: tile_grid takes the frame's size.
const int TILE_PX = 32;  // kTilePx: 8 invocations of 4 outputs along a pass, 4 workgroups of 8 across
const uint ZERO_TILE = 0x80000000u;  // horizontal entry: write zeros, no convolution
const int LIST_COUNTS = 4 * 32;

ivec2 tile_grid(int width_px, int height_px) { return (ivec2(width_px, height_px) + TILE_PX - 1) / TILE_PX; }
int tile_list_index(int field, int bucket, int pass) { return 2 * (32 * field + bucket - 1) + pass; }
int raw_mask_at(int field, int tile, int tiles) { return LIST_COUNTS + field * tiles + tile; }
int row_mask_at(int field, int tile, int tiles) { return LIST_COUNTS + (2 + field) * tiles + tile; }
