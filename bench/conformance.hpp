#pragma once
// The conformance measurements one method is held to, shared by the GoogleTest suite over the registry
// (tests/conformance/test_conformance.cpp) and `bokehbench check METHOD` (bench/commands/check.cpp): each builds
// its small frame, runs the method on the CPU reference or the GPU, and returns what it measured with
// the bound the method's own declarations (method.hpp) give it. Neither decides pass or fail here.
#include <string>
#include <vector>

#include "image.hpp"
#include "method.hpp"
#include "vk/context.hpp"
#include "vk/timestamps.hpp"

namespace bokeh::conformance {

enum class Backend { cpu, gpu };
const char* to_string(Backend backend);

// A measured value and the largest one the method's declarations allow.
struct Measure {
  double value = 0;
  double bound = 0;
  bool within() const { return value <= bound; }  // false for NaN
};

double max_abs(const Image& image);
double max_abs_diff(const Image& a, const Image& b);  // same shapes
double rgb_sum(const Image& image);
// Uniform RGB in [0, 4) inside a border of `margin_px` black pixels, reproducible for a seed.
Image random_image_in_black_border(int width_px, int height_px, int margin_px, unsigned seed);

// The method on one backend; ctx is only read for Backend::gpu (may be null for the CPU).
Image run(Backend backend, vk::Context* ctx, const Method& method, const Image& color, const Image& depth_m,
          const Lens& lens, const FilterOptions& options, std::vector<vk::PassTime>* passes = nullptr);

// Radius 0 everywhere (pillars 64x48 through a pinhole, f/1e12): max |out - in| against
// storage_tolerance x the largest value (+ 1e-6 of it for rounding).
Measure identity_at_radius_zero(Backend backend, vk::Context* ctx, const Method& method, const FilterOptions& options);

// A uniform 80x64 image (1, 2, 3) at a constant radius of twice the pattern's largest (so every pixel
// clamps to it): max |out - c| at least 2 r + 2 px from the borders, against (storage_tolerance + 1e-5)
// x the largest value. Every method blends samples with weights summing to one, so it stays uniform
// there; at varying radii even the exact scatter does not.
Measure uniform_stays_uniform(Backend backend, vk::Context* ctx, const Method& method, const FilterOptions& options);

// Light only inside a black border of 2 r + 2 px, every pixel at the largest radius:
// |sum(out) / sum(in) - 1| against storage_tolerance x the largest value x values / sum(in) + 1e-5
// (only meaningful where the method declares conserves_energy).
Measure energy_conserved(Backend backend, vk::Context* ctx, const Method& method, const FilterOptions& options);

// A procedural scene at 63x46 (not multiples of 4 or 8: partial blocks and workgroups), its lens set so
// radii reach 1.2x the pattern's largest (some pixels clamp): max |GPU - CPU| / the CPU's largest value
// against gpu_tolerance. `passes` receives the GPU's pass times; `finite` whether every GPU value is.
Measure gpu_matches_cpu(vk::Context& ctx, const Method& method, const FilterOptions& options,
                        const std::string& scene, std::vector<vk::PassTime>* passes = nullptr,
                        bool* finite = nullptr);

}  // namespace bokeh::conformance
