// naive: the quadratic gather of the FLAG paper, section 3.1.
#include "method.hpp"
#include "naive_gather.hpp"
#include "naive_gpu.hpp"

namespace bokeh::methods {

void declare_naive(std::vector<Method>& methods) {
  Method m;
  m.name = "naive";
  m.description = "naive quadratic gather, N x N samples at spacing k (FLAG paper 3.1)";
  m.precisions = {"f32"};
  // Same output for every block (bit for bit: each output adds its samples in the same order); only
  // the speed differs, by device. See shaders/naive/gather.comp.
  m.options = {naive_gather_block_option()};
  m.cpu_reference = [](const CpuInput& in) { return naive_gather(in.packed, in.options.pattern, in.threads); };
  m.make_gpu = make_naive_gpu;
  // Every pixel tests all N x N samples; it reads the packed image and writes the output once.
  m.work = [](const FilterOptions& o, int w, int h) {
    const double pixels = static_cast<double>(w) * h;
    return std::vector<PassWork>{{"gather", pixels * o.pattern.samples_per_pixel(), pixels * 16, pixels * 16}};
  };
  m.gpu_memory = [](const FilterOptions&, int, int, vk::Context*) { return MemoryUse{}; };
  m.cpu_memory_bytes = [](const FilterOptions&, int, int) { return std::uint64_t{0}; };
  // The same sums in the same order as the CPU: only f32 rounding of the GPU's fused operations.
  m.gpu_tolerance = [](const FilterOptions&) { return 1e-5; };
  m.storage_tolerance = [](const FilterOptions&) { return 0.0; };
  m.energy_note = "each source's contributions sum to its colour: weights are 1 / the discrete disc area";
  methods.push_back(std::move(m));
}

}  // namespace bokeh::methods
