#pragma once
// The exact reference every filter is judged against: each pixel spreads its colour uniformly over its
// own circle of confusion (a disc with exact area-weighted coverage at its edge), either summed
// (energy_sum) or composited front to back in depth order (depth_ordered). Any other aperture
// (aperture.hpp: n blades, curved blades) takes the disc's place everywhere below: its coverage of a
// pixel is the pixel square clipped against the polygon's edges (exact up to rounding), intersected
// with the disc for curved blades; its area is the sum of its coverages (n R^2 sin(2 pi / n) / 2 for
// straight blades, which the tests hold it to). Circle of confusion radius = circumradius.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "aperture.hpp"
#include "image.hpp"
#include "parallel.hpp"

namespace bokeh {

enum class ScatterComposite { energy_sum, depth_ordered };
std::string to_string(ScatterComposite mode);

// Geometry shared by both modes. Source pixel s (integer coordinates) is the unit square
// [sx, sx+1] x [sy, sy+1]; its disc has radius r = radius_px(s) and is centred on the pixel centre.
//   coverage_s(t) = area of (disc of s) ∩ (unit square of target pixel t), in closed form (circular
//                   segment integrals) in double precision: no approximation beyond rounding (the
//                   coverages of a disc sum to pi r^2 within 1e-12 relative for r <= 100; the tests hold
//                   them to that). Squares lying wholly inside the disc get exactly 1.
//   area_s        = sum over all integer pixel positions t (inside the image or not) of coverage_s(t),
//                   i.e. pi r^2 up to rounding; summing the same coverages we spread makes every source
//                   conserve its energy to rounding.
//   w_s(t)        = coverage_s(t) / area_s, so sum_t w_s(t) = 1.
// r <= 0.5 puts the disc inside its own pixel: w_s(s) = 1 and nothing else (the identity).
//
// The border convention (README, Accuracy): only pixels of the image are sources, each normalised by its
// whole disc; the share falling beyond the border is lost and nothing comes in from beyond it. Within
// the largest radius of the border a uniform image therefore darkens (to about a quarter at a corner);
// further in it stays uniform. Naive and FLAG follow this; methods that clamp to the edge or renormalise
// say so in their headers, and every result also carries its metrics over the interior alone.
// energy_sum:    out(t) = sum_s w_s(t) colour(s). Contributions landing outside the image are lost.
// depth_ordered: a source is a surface patch; w_s(t) is the fraction of target t's view through the
//   aperture that the patch occupies. Sources are taken front to back (ascending depth_m); sources of
//   exactly equal depth form one layer (order inside a layer does not matter). With a(t) the view filled
//   so far, a layer L with W = sum_{s in L} w_s(t) and C = sum_{s in L} w_s(t) colour(s) adds
//   f = min(1, (1 - a) / W) of itself:  rgb(t) += f C,  a(t) += f W.
//   Patches of one surface occupy disjoint parts of the aperture, so their shares add (a multiplicative
//   "over" of the pieces would leave e^-1 of an opaque blurred surface transparent); once a view is
//   full (a = 1) everything behind is hidden.
//   Hidden surfaces: the surface seen at t in the pinhole image (t's own pixel: depth d_t, radius r_t)
//   is taken to continue behind every nearer pixel and beyond the image border. Its disc centred on t
//   would have had the share
//     H = (sum of coverage over image pixels p with depth_m(p) < d_t + coverage falling off-image) / area
//   there; that share, up to a full view, is filled with the mean colour of the view so far:
//     out(t) = rgb(t) * (a + h) / a,  h = min(H, 1 - a).
//   So a blurred background keeps its brightness beside a sharp foreground and at the border. The rest
//   of the view stays dark rather than being invented: e.g. the in-focus backdrop hidden behind a
//   blurred point light's own pixel (dividing by a everywhere would put the light's full colour on that
//   pixel), or a hidden background behind a blurred foreground edge. Views within 1e-9 of full count as
//   full.
//   Radius 0 everywhere gives the identity: each target sees only its own pixel, with w = 1.
//
// color: >= 3 channels, linear RGB (channels beyond three are ignored). radius_px: 1 channel, finite
// and >= 0. depth_m: 1 channel, finite; read only by depth_ordered (may be an empty Image otherwise).
// Returns 3 channels. Throws std::invalid_argument on bad shapes or values. Cost grows with the sum of
// disc areas: a 800x600 frame with radii up to 40 px takes seconds on two cores.
Image exact_scatter(const Image& color, const Image& radius_px, const Image& depth_m, ScatterComposite mode,
                    int threads = default_cpu_threads(), const Aperture& aperture = {});

// The same result before rounding to float: RGB interleaved, row-major, width * height * 3 doubles.
// For checks finer than float resolution (energy conservation to 1e-9).
std::vector<double> exact_scatter_double(const Image& color, const Image& radius_px, const Image& depth_m,
                                         ScatterComposite mode, int threads = default_cpu_threads(),
                                         const Aperture& aperture = {});

// FNV-1a (64 bit) over the algorithm version, the cache format, mode, shapes (the frame size) and the bytes
// of colour and radius, and of depth for depth_ordered: the same inputs always name the same cached
// reference. The radius is computed from the depth, the lens and the CoC clamp, so the key covers them;
// a non-disc aperture adds its name (the disc's key is what it was before apertures existed).
std::uint64_t exact_scatter_key(const Image& color, const Image& radius_px, const Image& depth_m,
                                ScatterComposite mode, const Aperture& aperture = {});

// EXR files (float, lossless) under `directory`, one per key, so sweeps compute each reference once.
// Files are written atomically (write_file_atomically), so concurrent processes never read half a file.
// Each entry carries in its header the key it was computed for and a hash of its pixels; an entry is used
// only when both match (the key is recomputed from the inputs): one replaced by another valid image, left
// from an older format, or corrupted is recomputed, with a one-line note on stderr naming it.
class ExactReferenceCache {
 public:
  explicit ExactReferenceCache(std::filesystem::path directory = "build/reference-cache");

  // The cached reference for these inputs, computed with exact_scatter and stored on a miss, or when the
  // stored entry is unreadable or does not verify (its key, size or pixel hash).
  Image get(const Image& color, const Image& radius_px, const Image& depth_m, ScatterComposite mode,
            int threads = default_cpu_threads(), const Aperture& aperture = {});

  std::filesystem::path path_for(const Image& color, const Image& radius_px, const Image& depth_m,
                                 ScatterComposite mode, const Aperture& aperture = {}) const;
  const std::filesystem::path& directory() const { return directory_; }

 private:
  std::filesystem::path directory_;
};

}  // namespace bokeh
