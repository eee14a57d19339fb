// FLAG 3D-buffer memory: the paper's printed figures and the driver's allocation sizes.
#include <gtest/gtest.h>

#include "flag_memory.hpp"
#include "flag_gpu.hpp"
#include "flag_reduced.hpp"
#include "method.hpp"
#include "vk/memory.hpp"

#include <cstdint>
#include <vector>

namespace bokeh {
namespace {

const GatherPattern k41{41, 2};

// The CPU FLAG reference fuses its passes strip by strip: besides a disc index a pixel (4 B) it holds,
// per thread, one source row's layers and the output rows in flight (2 n k + 1, at most the height) of a
// strip, sized to stay within about 256 KiB (a core's L2): the same at 8192^2, where the whole 3D buffer
// would be 16 GiB, as at 800x600.
TEST(FlagMemory, CpuReferenceHoldsNoLayerBuffer) {
  const Method& flag = find_method("flag");
  const std::uint64_t threads = default_cpu_threads();
  for (const GatherPattern& pattern : {GatherPattern{9, 2}, k41, GatherPattern{153, 2}, GatherPattern{41, 1}}) {
    const FilterOptions o = flag.defaults(pattern);
    for (const auto& [w, h] : std::vector<std::pair<int, int>>{{64, 40}, {800, 600}, {8192, 8192}}) {
      const std::uint64_t index = static_cast<std::uint64_t>(w) * h * 4, bytes = flag.cpu_memory_bytes(o, w, h);
      ASSERT_GT(bytes, index) << pattern.size_n << " " << w << "x" << h;
      EXPECT_LE(bytes - index, threads * (288u << 10)) << pattern.size_n << " " << w << "x" << h;  // 256 KiB + rounding
      // At least one thread's scratch for a strip of 4 columns (the narrowest vector).
      const int rows = pattern.layers() + std::min(h, 2 * pattern.half() * pattern.spacing_px + 1);
      EXPECT_GE(bytes - index, rows * 12ull * 4) << pattern.size_n << " " << w << "x" << h;
    }
  }
  FilterOptions o = flag.defaults(k41);
  o.precision = "unorm16_bracketed";  // brackets whole rows: the whole buffer, and says so
  EXPECT_EQ(flag.cpu_memory_bytes(o, 8192, 8192), 8192ull * 8192 * 21 * 12);
}

// The CPU reference's work model, which a CPU point's throughput divides by its time: the fused
// reference reads the packed input (4 floats a pixel) and writes the image (3) once, with both passes'
// taps (N row samples and N layer sums a pixel); the paths that keep layers in memory move them as the
// GPU passes do.
TEST(FlagMemory, CpuWorkCountsNoLayerTraffic) {
  const Method& flag = find_method("flag");
  const auto total = [](const std::vector<PassWork>& passes) {
    PassWork sum;
    for (const PassWork& p : passes) sum.taps += p.taps, sum.bytes_read += p.bytes_read, sum.bytes_written += p.bytes_written;
    return sum;
  };
  FilterOptions o = flag.defaults(GatherPattern{81, 2});
  const double pixels = 800.0 * 600;
  const PassWork cpu = total(flag.cpu_work(o, 800, 600)), gpu = total(flag.work(o, 800, 600));
  EXPECT_EQ(cpu.taps, 2 * 81 * pixels);
  EXPECT_EQ(cpu.taps, gpu.taps);
  EXPECT_EQ(cpu.bytes_read, 16 * pixels);
  EXPECT_EQ(cpu.bytes_written, 12 * pixels);
  EXPECT_EQ(gpu.bytes_written - 16 * pixels, 41 * 8 * pixels);  // the GPU's f16 layers, which the CPU never writes
  o.precision = "unorm16_bracketed";  // flag_blur_reference's whole buffer: the GPU's model
  EXPECT_EQ(total(flag.cpu_work(o, 800, 600)).bytes_written, total(flag.work(o, 800, 600)).bytes_written);
}

// A fused pass keeps its layers in registers: what it keeps (bytes_kept, its speed counted as the
// unfused passes' work) is what the two passes over the whole buffer write and read, for the disc the
// paper's 332 MB at 1080p / 41x41 f16 each way, and for a shape its own layers.
TEST(FlagMemory, FusedPassKeepsWhatTheUnfusedPassesMove) {
  const Method& flag = find_method("flag");
  const auto pass = [](const std::vector<PassWork>& passes, const std::string& name) {
    for (const PassWork& p : passes)
      if (p.pass == name) return p;
    ADD_FAILURE() << "no pass " << name;
    return PassWork{};
  };
  for (const std::string aperture : {"disc", "blades6", "blades5"}) {
    FilterOptions fused = flag.defaults(k41), full = fused;
    fused.aperture = full.aperture = parse_aperture(aperture);
    fused.values["layer_buffer"] = static_cast<double>(FlagLayerBuffer::registers);
    full.values["layer_buffer"] = static_cast<double>(FlagLayerBuffer::full);
    const auto unfused = flag.work(full, 1920, 1080);
    const double layers_moved = pass(unfused, "horizontal").bytes_written + pass(unfused, "vertical").bytes_read;
    EXPECT_EQ(pass(flag.work(fused, 1920, 1080), "fused").bytes_kept, layers_moved) << aperture;
    EXPECT_EQ(pass(unfused, "horizontal").bytes_kept, 0) << aperture;
    if (aperture == "disc") {
      EXPECT_EQ(layers_moved, 2 * flag_paper_bytes(1920, 1080, k41, LayerPrecision::f16, 1));
      EXPECT_EQ(pass(flag.cpu_work(fused, 1920, 1080), "fused").bytes_kept, layers_moved);  // the CPU's strips
    }
  }
}

// Streamed layers: the ring of B + 2 n k rows as the model sizes it and as the driver allocates it.
// The goal at 1080p / 41x41 (k = 1) f16: <= 16 MiB on lavapipe's auto band (12 rows: 52 rows of
// 1920 x 21 texels), against 332 MiB for the full buffer; explicit bands set the ring's rows.
TEST(FlagMemory, StreamedRingIsBandPlusTwiceTheReach) {
  const Method& flag = find_method("flag");
  FilterOptions o = flag.defaults({41, 1});
  o.values["layer_buffer"] = static_cast<double>(FlagLayerBuffer::streamed);
  const MemoryUse model = flag.gpu_memory(o, 1920, 1080, nullptr);  // no device: lavapipe's auto
  EXPECT_EQ(model.details["streamed"]["band_rows"], 12);
  EXPECT_EQ(model.details["extent"]["height"], 52);
  EXPECT_EQ(model.bytes, 1920ull * 52 * 21 * 8);
  EXPECT_LE(model.bytes, 16ull << 20);
  o.values["band_rows"] = 100;
  EXPECT_EQ(flag.gpu_memory(o, 1920, 1080, nullptr).details["extent"]["height"], 140);
  o.values["band_rows"] = 5000;  // more than the frame: the full buffer's rows, no more
  EXPECT_EQ(flag.gpu_memory(o, 1920, 1080, nullptr).details["extent"]["height"], 1080);
  // 4K / 81x81: the full buffer's 2.7 GB passes lavapipe's 2 GiB heap; the ring (auto: the 8-row floor,
  // 2 n k = 80 rows: 106 MiB) does not.
  FilterOptions big = flag.defaults({81, 1});
  EXPECT_GT(flag.gpu_memory(big, 3840, 2160, nullptr).bytes, 2ull << 30);
  big.values["layer_buffer"] = static_cast<double>(FlagLayerBuffer::streamed);
  EXPECT_EQ(flag.gpu_memory(big, 3840, 2160, nullptr).bytes, 3840ull * 88 * 41 * 8);
  vk::Context ctx;
  big.values["band_rows"] = 8;
  EXPECT_GE(flag.gpu_memory(big, 3840, 2160, &ctx).bytes, 3840ull * 88 * 41 * 8);
  // The CPU reference streams the same way: its ring (f32 rgb, rows of whole vectors), not the frame.
  EXPECT_LT(flag.cpu_memory_bytes(big, 3840, 2160), 3840ull * 2160 * 41 * 12 / 8);
}

// Small buffers share blocks (the best-practices layer's advice); each keeps its own bytes, a freed
// range is reused, and a buffer over the sub-allocation limit gets memory of its own.
TEST(DeviceMemory, SmallBuffersShareBlocksAndKeepTheirOwnData) {
  vk::Context ctx;
  const VkBufferUsageFlags usage =
      VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  {
    std::vector<vk::Buffer> buffers;
    for (int i = 0; i < 64; ++i) {
      buffers.emplace_back(ctx, 16 + 4 * i, usage);
      std::vector<std::uint32_t> words((16 + 4 * i) / 4, static_cast<std::uint32_t>(i));
      vk::upload(ctx, buffers.back(), words.data(), words.size() * 4);
    }
    const std::size_t blocks = ctx.memory_blocks().block_count();
    EXPECT_LE(blocks, 2u) << "64 small buffers (and their staging copies) in at most one device and one host block";
    for (int i = 0; i < 64; ++i) {
      std::vector<std::uint32_t> words((16 + 4 * i) / 4, 0xdeadbeef);
      vk::download(ctx, buffers[i], words.data(), words.size() * 4);
      for (std::uint32_t w : words) ASSERT_EQ(w, static_cast<std::uint32_t>(i)) << "buffer " << i;
    }
    vk::Buffer large(ctx, vk::Allocation::kMaxSubAllocation + 1, usage);
    EXPECT_EQ(ctx.memory_blocks().block_count(), blocks) << "a large buffer has memory of its own";
  }
  const std::size_t blocks = ctx.memory_blocks().block_count();
  std::vector<vk::Buffer> again;
  for (int i = 0; i < 64; ++i) again.emplace_back(ctx, vk::Allocation::kMaxSubAllocation / 8, usage);
  EXPECT_EQ(ctx.memory_blocks().block_count(), blocks) << "freed ranges merge and are reused";
}

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
    for (int scale : flag_buffer_scales()) {
      const auto e = flag_buffer_extent(1920, 1080, k41, scale);
      const auto bytes = vk::image_3d_requirement_bytes(ctx, layer_format(p), e.width, e.height, e.layers);
      const auto texels = flag_texel_bytes(1920, 1080, k41, p, scale);
      EXPECT_GE(bytes, texels);
      EXPECT_LT(bytes, texels + texels / 8) << "padding over 12.5%: " << bytes << " vs " << texels;
    }
}

}  // namespace
}  // namespace bokeh
