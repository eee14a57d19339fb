// One suite over the registry (the measurements: bench/conformance.hpp, which `bokehbench check`
// shares): every method x precision x buffer scale it accepts, each at its
// defaults and with every other choice of each enumerated option (one option at a time: a GPU
// block shape, adaptive = on), checked against what the method itself declares (method.hpp). A new
// method or option is covered without editing this file.
//   GPU vs CPU reference: max |GPU - CPU| <= gpu_tolerance x the reference's largest value, and the
//   passes the GPU stamps are the ones the work model names, on hoops and on fully_defocused.
//   Radius 0 (a pinhole lens) is the identity, up to storage_tolerance x the largest value.
//   Energy: at a constant radius with a black border wider than any kernel, the output's total equals
//   the input's (methods that declare they conserve it), up to storage_tolerance x the largest value
//   on every output value.
// Apertures (issue 23): each method that declares it can draw a non-disc aperture runs every check
// above at its defaults with each of a pentagon pointing up (not vertically symmetric), a hexagon at
// rotation 0 and at 15 degrees (off its 60-degree grid), and rotated curved blades, the lens carrying
// the same aperture (and with adaptive = on, where a method has that option and draws the shape).
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>

#include "conformance.hpp"
#include "gpu_test_support.hpp"
#include "method.hpp"

namespace bokeh {
namespace {

using namespace bokeh::test;

struct Config {
  const Method* method;
  FilterOptions options;
};

// The options a configuration sets away from their defaults, as "key:choice" ("" at the defaults).
std::string choices_text(const Config& c) {
  std::string text;
  for (const auto& spec : c.method->options)
    if (const double v = c.options.number(spec.key); v != spec.default_value)
      text += (text.empty() ? "" : " ") + spec.key + ":" + spec.to_json(v).get<std::string>();
  return text;
}

void PrintTo(const Config& c, std::ostream* os) {
  *os << c.method->name << " " << c.options.precision << " 1/" << c.options.buffer_scale << " " << choices_text(c)
      << " " << c.options.aperture.name();
}

// N = 9 at k = 2: radii up to 8 px, four rows of FLAG layers, kernels of 8..11 px.
std::vector<Config> all_configs() {
  std::vector<Config> configs;
  for (const Method& m : registered_methods())
    for (const auto& precision : m.precisions)
      for (int scale : m.buffer_scales) {
        FilterOptions o = m.defaults({9, 2});
        o.precision = precision;
        o.buffer_scale = scale;
        configs.push_back({&m, o});
        for (const auto& spec : m.options)
          for (std::size_t choice = 0; choice < spec.choices.size(); ++choice) {
            if (static_cast<double>(choice) == spec.default_value) continue;
            FilterOptions varied = o;
            varied.values[spec.key] = static_cast<double>(choice);
            // A choice this precision or scale cannot run (FLAG's layer_buffer = registers) is refused by
            // the runner with its reason (FlagRegisters tests that), not conformed.
            if (m.unsupported && !m.unsupported(varied, 63, 46).empty()) continue;
            configs.push_back({&m, varied});
          }
      }
  for (const Method& m : registered_methods())
    for (const char* shape : {"blades5", "blades6", "blades6-rot15", "blades7-rot20-curv0.5"}) {
      FilterOptions o = m.defaults({9, 2});
      o.aperture = parse_aperture(shape);
      if (aperture_unsupported(m, o).empty()) configs.push_back({&m, o});
      // adaptive = on too, where the method draws the shape with it (its tile map's bound must hold).
      if (const OptionSpec* adaptive = m.option("adaptive"); adaptive && adaptive->choices.size() == 2) {
        o.values["adaptive"] = 1;
        if (aperture_unsupported(m, o).empty()) configs.push_back({&m, o});
      }
    }
  return configs;
}

void skip_if_device_lacks(const Method& m, const FilterOptions& o) {
  if (const std::string missing = context().unmet(m.needs(o)); !missing.empty())
    GTEST_SKIP() << m.name << " needs " << missing << ", which " << context().info().name << " lacks";
}

class Conformance : public ::testing::TestWithParam<Config> {};

TEST_P(Conformance, GpuMatchesCpuReferenceWithinTheStatedBound) {
  const Config c = GetParam();
  skip_if_device_lacks(*c.method, c.options);
  // fully_defocused: every pixel blurs, the border's included, so each method's edge handling (clamped,
  // skipped or renormalised samples, partial workgroups) is held to the same bound as the rest.
  for (const char* scene : {"hoops", "fully_defocused"}) {
    SCOPED_TRACE(scene);
    std::vector<vk::PassTime> passes;
    bool finite = false;
    const conformance::Measure m = conformance::gpu_matches_cpu(context(), *c.method, c.options, scene, &passes, &finite);
    // The work model names the passes the GPU driver stamps, in the same order (CoC first).
    std::vector<std::string> timed, modelled = {"coc"};
    for (const auto& p : passes) timed.push_back(p.pass);
    const FilterOptions as_run = c.method->on_device ? c.method->on_device(c.options, &context().info()) : c.options;
    for (const auto& w : c.method->work(as_run, 63, 46)) modelled.push_back(w.pass);
    EXPECT_EQ(timed, modelled);
    ASSERT_TRUE(finite);
    std::printf("[conformance] %s %s %s 1/%d %s: GPU vs CPU %.3g of the largest value (bound %.3g)\n", scene,
                c.method->name.c_str(), c.options.precision.c_str(), c.options.buffer_scale, choices_text(c).c_str(),
                m.value, m.bound);
    EXPECT_LE(m.value, m.bound);
  }
}

TEST_P(Conformance, RadiusZeroIsTheIdentity) {
  const Config c = GetParam();
  skip_if_device_lacks(*c.method, c.options);
  for (const auto backend : {conformance::Backend::cpu, conformance::Backend::gpu}) {
    const conformance::Measure m = conformance::identity_at_radius_zero(backend, &context(), *c.method, c.options);
    EXPECT_LE(m.value, m.bound) << conformance::to_string(backend);
  }
}

// Every method, energy-conserving or not (spiral: see its energy_note), blends samples with weights
// summing to one, so a uniform image at a constant radius stays uniform away from the borders.
TEST_P(Conformance, UniformImageStaysUniformAwayFromTheBorders) {
  const Config c = GetParam();
  skip_if_device_lacks(*c.method, c.options);
  for (const auto backend : {conformance::Backend::cpu, conformance::Backend::gpu}) {
    const conformance::Measure m = conformance::uniform_stays_uniform(backend, &context(), *c.method, c.options);
    EXPECT_LE(m.value, m.bound) << conformance::to_string(backend);
  }
}

class EnergyConservation : public ::testing::TestWithParam<Config> {};

TEST_P(EnergyConservation, EnergyIsConservedAwayFromTheBorders) {
  const Config c = GetParam();
  skip_if_device_lacks(*c.method, c.options);
  // Every pixel behind the focus at the largest radius; light only inside a margin of twice it.
  for (const auto backend : {conformance::Backend::cpu, conformance::Backend::gpu}) {
    const conformance::Measure m = conformance::energy_conserved(backend, &context(), *c.method, c.options);
    EXPECT_LE(m.value, m.bound) << conformance::to_string(backend) << ": |sum(out) / sum(in) - 1|; "
                                << c.method->energy_note;
  }
}

std::string config_name(const ::testing::TestParamInfo<Config>& info) {
  std::string name = info.param.method->name + "_" + info.param.options.precision + "_scale" +
                     std::to_string(info.param.options.buffer_scale);
  const std::string choices = choices_text(info.param);
  if (!choices.empty()) name += "_";
  for (char ch : choices) name += std::isalnum(static_cast<unsigned char>(ch)) ? ch : '_';
  if (!info.param.options.aperture.is_disc())
    for (char ch : "_" + info.param.options.aperture.name()) name += std::isalnum(static_cast<unsigned char>(ch)) ? ch : '_';
  return name;
}

// The configurations of the methods that declare their light conserved at a constant radius.
std::vector<Config> energy_conserving_configs() {
  std::vector<Config> configs = all_configs();
  std::erase_if(configs, [](const Config& c) { return !c.method->conserves_energy; });
  return configs;
}

INSTANTIATE_TEST_SUITE_P(Registry, Conformance, ::testing::ValuesIn(all_configs()), config_name);
INSTANTIATE_TEST_SUITE_P(Registry, EnergyConservation, ::testing::ValuesIn(energy_conserving_configs()), config_name);

// Every method declares what the harness reads of it.
TEST(Registry, EveryMethodDeclaresItsModels) {
  for (const Method& m : registered_methods()) {
    SCOPED_TRACE(m.name);
    EXPECT_FALSE(m.precisions.empty());
    EXPECT_TRUE(m.cpu_reference && m.make_gpu && m.work && m.gpu_memory && m.cpu_memory_bytes && m.gpu_tolerance &&
                m.storage_tolerance);
    const FilterOptions o = m.defaults({9, 2});
    EXPECT_NO_THROW(check_options(m, o));
    const auto work = m.work(o, 64, 48);
    ASSERT_FALSE(work.empty());
    for (const auto& pass : work) EXPECT_GT(pass.taps + pass.bytes_read + pass.bytes_written, 0) << pass.pass;
  }
}

}  // namespace
}  // namespace bokeh
