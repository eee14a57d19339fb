// Method packages (kernels/package/): the worked packages under shaders/packages/ against the built-ins
// and the exact reference, and every way a manifest or shader can be wrong refused with its file (and
// line) named, before any work.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>

#include <fmt/format.h>

#include "coc.hpp"
#include "gpu_test_support.hpp"
#include "method.hpp"
#include "package.hpp"
#include "run.hpp"
#include "scene.hpp"
#include "test_support.hpp"

namespace bokeh {
namespace {

namespace fs = std::filesystem;
using namespace bokeh::test;

const fs::path kPackages = fs::path(BOKEH_SOURCE_DIR) / "shaders" / "packages";

// A package folder of its own under the test's temporary directory: the hexagon_rhombi package with
// `edit` applied to its manifest text and `files` written beside it.
fs::path variant(const std::string& name, const std::function<void(std::string&)>& edit,
                 const std::map<std::string, std::string>& files = {}) {
  const fs::path dir = fs::temp_directory_path() / fmt::format("bokehbench-test-package-{}-{}", getpid(), name);
  fs::remove_all(dir);
  fs::copy(kPackages / "hexagon_rhombi", dir, fs::copy_options::recursive);
  std::ifstream in(dir / kPackageManifest);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  edit(text);
  std::ofstream(dir / kPackageManifest) << text;
  for (const auto& [file, content] : files) std::ofstream(dir / file) << content;
  return dir;
}

std::string load_error(const fs::path& dir) {
  try {
    load_package(dir.string());
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(loaded without an error)";
}

void replace(std::string& text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
}

// The re-expressed hexagon: the same image as the built-in bit for bit on the GPU (the same shader
// code, compiled at run time instead of at build time), the same CPU reference, work and memory model.
TEST(Package, HexagonRhombiIsTheBuiltInHexagonBitForBit) {
  const Method& package = load_package((kPackages / "hexagon_rhombi").string());
  const Method& builtin = find_method("hexagon");
  EXPECT_EQ(package.name, "hexagon_rhombi");
  EXPECT_EQ(package.package["name"], "hexagon_rhombi");
  EXPECT_EQ(package.package["hash"].get<std::string>().size(), 16u);
  EXPECT_EQ(&find_method("hexagon_rhombi"), &package);  // by name once loaded
  const Scene s = make_scene("hoops", 160, 120);
  const FilterOptions po = package.defaults({21, 2}), bo = builtin.defaults({21, 2});
  const Image from_package = run_gpu(context(), package, s.color, s.depth_m, s.lens, po);
  const Image from_builtin = run_gpu(context(), builtin, s.color, s.depth_m, s.lens, bo);
  EXPECT_TRUE(same_bits(from_package, from_builtin));
  const Image cpu = run_cpu(package, s.color, s.depth_m, s.lens, po, 2);
  EXPECT_TRUE(same_bits(cpu, run_cpu(builtin, s.color, s.depth_m, s.lens, bo, 2)));
  EXPECT_LE(max_abs_diff(from_package, cpu), package.gpu_tolerance(po) * 1e4);  // hoops' lights reach ~1e4
  const auto pw = package.work(po, 160, 120), bw = builtin.work(bo, 160, 120);
  ASSERT_EQ(pw.size(), bw.size());
  for (std::size_t i = 0; i < pw.size(); ++i) {
    EXPECT_EQ(pw[i].pass, bw[i].pass);
    EXPECT_EQ(pw[i].taps, bw[i].taps) << pw[i].pass;
    EXPECT_EQ(pw[i].bytes_read, bw[i].bytes_read) << pw[i].pass;
    EXPECT_EQ(pw[i].bytes_written, bw[i].bytes_written) << pw[i].pass;
  }
  EXPECT_EQ(package.gpu_memory(po, 160, 120, nullptr).bytes, builtin.gpu_memory(bo, 160, 120, nullptr).bytes);
}

// Memory declared = memory allocated: the package's buffers as its expressions size them.
TEST(Package, DeclaredMemoryIsWhatIsAllocated) {
  for (const char* name : {"hexagon_rhombi", "tile_scatter"}) {
    const Method& m = load_package((kPackages / name).string());
    const Scene s = make_scene("hoops", 200, 150);
    const FilterOptions o = m.defaults({41, 2});
    gpu::GpuFrame frame(context(), s.color, s.depth_m, s.lens, o.pattern);
    const auto filter = m.make_gpu(frame, o);
    const std::uint64_t declared = m.gpu_memory(o, 200, 150, nullptr).bytes;
    EXPECT_GE(filter->intermediate_bytes(), declared) << name;
    EXPECT_LE(filter->intermediate_bytes(), declared + 4096) << name;  // lavapipe pads to 64 B a buffer
  }
}

// The filter none of the built-ins is: a GPU-only package, finite everywhere, the identity where
// nothing is blurred, and within a few percent of the exact reference on a defocused scene.
TEST(Package, TileScatterIsGpuOnlyAndSane) {
  const Method& m = load_package((kPackages / "tile_scatter").string());
  EXPECT_FALSE(m.cpu_reference);
  const FilterOptions o = m.defaults({21, 2});
  Scene s = make_scene("hoops", 160, 120);
  const Image out = run_gpu(context(), m, s.color, s.depth_m, s.lens, o);
  for (float v : out.pixels) ASSERT_TRUE(std::isfinite(v));
  // In focus everywhere (depth at the focus distance): every tile takes the copy path.
  Image focused_depth(160, 120, 1, static_cast<float>(s.lens.focus_distance_m));
  const Image same = run_gpu(context(), m, s.color, focused_depth, s.lens, o);
  EXPECT_TRUE(same_bits(same, s.color));
}

TEST(Package, ManifestErrorsNameTheFileAndTheField) {
  EXPECT_NE(load_error(fs::temp_directory_path() / "no-such-package").find("has no bokeh-package.json"), std::string::npos);
  const auto expect = [](const std::string& name, const std::function<void(std::string&)>& edit, const std::string& wanted) {
    const std::string error = load_error(variant(name, edit));
    EXPECT_NE(error.find(wanted), std::string::npos) << error;
    EXPECT_NE(error.find("bokeh-package.json"), std::string::npos) << error;
  };
  expect("json", [](std::string& t) { t.pop_back(), t.pop_back(); }, "not valid JSON");
  expect("builtin_name", [](std::string& t) { replace(t, "\"hexagon_rhombi\"", "\"naive\""); }, "is a built-in method's name");
  expect("field", [](std::string& t) { replace(t, "\"samples_pattern\"", "\"sample_pattern\""); },
         "sample_pattern is not a field of the manifest");
  expect("no_builtin", [](std::string& t) { replace(t, "{\"builtin\": \"hexagon\"}", "{}"); }, "cpu_reference.builtin is missing");
  expect("format", [](std::string& t) { replace(t, "\"rgba32f\"", "\"rgb9e5\""); }, "buffers[0].format");
  expect("variable", [](std::string& t) { replace(t, "\"ceil(width / 4)\"", "\"ceil(wdth / 4)\""); },
         "passes[0].invocations[0]");
  expect("syntax", [](std::string& t) { replace(t, "\"pixels * 16\"", "\"pixels * * 16\""); }, "pixels * * 16");
  expect("negative", [](std::string& t) { replace(t, "\"height\"", "\"-height\""); }, "not a whole number >= 0");
  expect("reference", [](std::string& t) { replace(t, "{\"builtin\": \"hexagon\"}", "{\"builtin\": \"hexagons\"}"); },
         "'hexagons' is not a built-in method");
}

// A shader that does not compile is refused at load, with glslang's message naming the file and line
// (in an included file: that file's name).
TEST(Package, CompileErrorsNameTheFileAndLine) {
  const fs::path broken = variant("glsl", [](std::string&) {},
                                  {{"second.comp", "#version 450\nlayout(local_size_x = 8) in;\nvoid main() {\n  undeclared_name = 1;\n}\n"}});
  const std::string error = load_error(broken);
  EXPECT_NE(error.find("second.comp does not compile"), std::string::npos) << error;
  EXPECT_TRUE(std::regex_search(error, std::regex("second\\.comp:4: .*undeclared_name"))) << error;
  const fs::path included = variant("include", [](std::string& t) { replace(t, "\"first.comp\"", "\"uses_broken.comp\""); },
                                    {{"uses_broken.comp", "#version 450\n#extension GL_GOOGLE_include_directive : require\n"
                                                          "#include \"broken.glsl\"\nvoid main() {}\n"},
                                     {"broken.glsl", "// fine\nfloat f( {\n"}});
  const std::string include_error = load_error(included);
  EXPECT_TRUE(std::regex_search(include_error, std::regex("broken\\.glsl:2: "))) << include_error;
  const fs::path missing = variant("missing_include", [](std::string& t) { replace(t, "\"first.comp\"", "\"missing.comp\""); },
                                   {{"missing.comp", "#version 450\n#extension GL_GOOGLE_include_directive : require\n"
                                                     "#include \"nowhere.glsl\"\nvoid main() {}\n"}});
  const std::string missing_error = load_error(missing);
  EXPECT_TRUE(std::regex_search(missing_error, std::regex("missing\\.comp:3: .*nowhere\\.glsl"))) << missing_error;
}

// Two versions of one package load side by side (the second named NAME@HASH8), and FOLDER@REV reads
// the folder as a git revision had it.
TEST(Package, VersionsLoadSideBySideAndFromGitRevisions) {
  const fs::path repo = fs::temp_directory_path() / fmt::format("bokehbench-test-package-repo-{}", getpid());
  fs::remove_all(repo);
  fs::create_directories(repo);
  fs::copy(kPackages / "hexagon_rhombi", repo / "my_dof", fs::copy_options::recursive);
  const std::string git = fmt::format("git -C '{}' -c user.name=t -c user.email=t@t ", repo.string());
  ASSERT_EQ(std::system((git + "init -q && " + git + "add -A && " + git + "commit -qm v1").c_str()), 0);
  std::ofstream(repo / "my_dof" / "README.md") << "an edit after the commit\n";
  const Method& now = load_package((repo / "my_dof").string());
  const Method& then = load_package((repo / "my_dof").string() + "@HEAD");
  EXPECT_NE(&now, &then);
  EXPECT_NE(now.package["hash"], then.package["hash"]);  // the edit changed the content hash
  EXPECT_EQ(then.package["rev"], "HEAD");
  EXPECT_TRUE(std::regex_match(then.name, std::regex("hexagon_rhombi@[0-9a-f]{8}"))) << then.name;
  EXPECT_EQ(&load_package((repo / "my_dof").string() + "@HEAD"), &then);  // once per folder and revision
  const std::string error = load_error(repo.string() + "/my_dof@no-such-rev");
  EXPECT_NE(error.find("no package at that revision"), std::string::npos) << error;
}

}  // namespace
}  // namespace bokeh
