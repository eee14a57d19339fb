// FLAG 3D-buffer memory: the paper's printed figures and the driver's allocation sizes.
#include <gtest/gtest.h>

#include "flag_memory.hpp"
#include "flag_gpu.hpp"
#include "vk/memory.hpp"

namespace bokeh {
namespace {

const GatherPattern k41{41, 2};

TEST(FlagMemory, PaperConventionReproducesPrintedFigures) {
  // Section 3.2.4: 332 MB at 1080p, 41x41, RGBA16F; section 5: 42 MB half, 5.2 MB quarter (MiB).
  EXPECT_EQ(flag_paper_bytes(1920, 1080, k41, LayerPrecision::f16, 1), 348364800.0);
  EXPECT_NEAR(flag_paper_bytes(1920, 1080, k41, LayerPrecision::f16, 1) / kMiB, 332.0, 0.5);
  EXPECT_NEAR(flag_paper_bytes(1920, 1080, k41, LayerPrecision::f16, 2) / kMiB, 42.0, 0.5);
  EXPECT_NEAR(flag_paper_bytes(1920, 1080, k41, LayerPrecision::f16, 4) / kMiB, 5.2, 0.05);
}

TEST(FlagMemory, WholeTexelExtents) {
  const auto half = flag_buffer_extent(1920, 1080, k41, 2), quarter = flag_buffer_extent(1920, 1080, k41, 4);
  EXPECT_EQ(half.width, 960);
  EXPECT_EQ(half.height, 540);
  EXPECT_EQ(half.layers, 11);
  EXPECT_EQ(quarter.layers, 6);
  EXPECT_EQ(flag_texel_bytes(1920, 1080, k41, LayerPrecision::f16, 2), 960ull * 540 * 11 * 8);
  EXPECT_EQ(flag_texel_bytes(1920, 1080, k41, LayerPrecision::f32, 1), 1920ull * 1080 * 21 * 16);
  EXPECT_THROW(flag_buffer_extent(1920, 1080, k41, 3), std::invalid_argument);
}

TEST(FlagMemory, DriverAllocatesAtLeastTheTexels) {
  vk::Context ctx;
  for (LayerPrecision p : {LayerPrecision::f16, LayerPrecision::f32})
    for (int scale : {1, 2, 4}) {
      const auto e = flag_buffer_extent(1920, 1080, k41, scale);
      const auto bytes = vk::image_3d_requirement_bytes(ctx, layer_format(p), e.width, e.height, e.layers);
      const auto texels = flag_texel_bytes(1920, 1080, k41, p, scale);
      EXPECT_GE(bytes, texels);
      EXPECT_LT(bytes, texels + texels / 8) << "padding over 12.5%: " << bytes << " vs " << texels;
    }
}

}  // namespace
}  // namespace bokeh
