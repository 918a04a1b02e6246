// The files a scene is read from (kernel/scene/input_file.hpp): a scene, a model file, an MJCF
// include and the model file a scene wraps are each read only when they are a regular file
// within their cap, and refused by name otherwise (a FIFO, a device, a directory, a file too
// large); text nested too deep is refused at its place before anything recurses over it. Each
// load that once hung runs in a child process with a time limit (tests/support/in_child.hpp), so
// a regression fails its test instead of hanging the suite.
#include <sys/stat.h>
#include <sys/types.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "limber/kernel/scene/scene_file.hpp"
#include "tests/support/in_child.hpp"
#include "tests/support/test_directory.hpp"

namespace limber {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;
using testing::in_child;
using testing::test_directory;
namespace fs = std::filesystem;

constexpr const char* kFifo = "cannot read file: not a regular file but a FIFO";

fs::path write(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

fs::path fifo(const fs::path& path) {
  EXPECT_EQ(::mkfifo(path.c_str(), 0600), 0) << path;
  return path;
}

// What loading `path` gives, in a child process: "loaded N bodies", or "error: <message>".
std::string load_in_child(const fs::path& path) {
  const testing::ChildOutcome outcome = in_child([&] {
    const Scene scene = load_scene_file(path);
    return "loaded " + std::to_string(scene.model.bodies.size()) + " bodies";
  });
  EXPECT_EQ(outcome.signal, 0) << "loading " << path << ": " << outcome.ending();
  return outcome.output;
}

// A small MJCF model: one hinged sphere.
const std::string kArm =
    "<mujoco>\n  <worldbody>\n    <body name=\"arm\">\n      <joint type=\"hinge\"/>\n"
    "      <geom type=\"sphere\" size=\".1\"/>\n    </body>\n  </worldbody>\n</mujoco>\n";

// ---- Only regular files are read

TEST(InputFiles, AFifoAsASceneOrModelFileIsRefusedWithoutWaiting) {
  const fs::path dir = test_directory();
  for (const char* name : {"scene.json", "model.xml", "robot.urdf"}) {
    const fs::path path = fifo(dir / name);
    EXPECT_EQ(load_in_child(path), "error: " + path.string() + ": " + kFifo + " (a named pipe: reading it would wait for a writer)");
  }
}

TEST(InputFiles, AFifoAsAnIncludeIsRefusedAtTheInclude) {
  const fs::path dir = test_directory();
  const fs::path part = fifo(dir / "part.xml");
  const fs::path main = write(dir / "main.xml", "<mujoco>\n  <include file=\"part.xml\"/>\n</mujoco>\n");
  const std::string message = load_in_child(main);
  EXPECT_THAT(message, StartsWith("error: " + main.string() + ":2: <include file>: " + part.string() + ": " + kFifo)) << message;
}

TEST(InputFiles, AFifoAsAWrappedModelFileIsRefused) {
  const fs::path dir = test_directory();
  const fs::path model = fifo(dir / "arm.xml");
  const fs::path scene = write(dir / "scene.json", R"({"limber_scene": 1, "model": "arm.xml"})");
  const std::string message = load_in_child(scene);
  EXPECT_THAT(message, StartsWith("error: " + scene.string() + ": " + model.string() + ": " + kFifo)) << message;
}

TEST(InputFiles, ADeviceThatNeverEndsIsRefusedAsScenesModelsAndIncludes) {
  const fs::path dir = test_directory();
  const std::string device = "cannot read file: not a regular file but a character device";
  EXPECT_THAT(load_in_child("/dev/zero"), StartsWith("error: /dev/zero: " + device));
  const fs::path main = write(dir / "main.xml", "<mujoco>\n  <include file=\"/dev/zero\"/>\n</mujoco>\n");
  const std::string message = load_in_child(main);
  EXPECT_THAT(message, StartsWith("error: " + main.string() + ":2: <include file>: /dev/zero: " + device)) << message;
}

TEST(InputFiles, ADirectoryIsRefusedAsAModelFileAndAsAnInclude) {
  const fs::path dir = test_directory();
  fs::create_directories(dir / "arm.xml");
  fs::create_directories(dir / "part.xml");
  EXPECT_EQ(load_in_child(dir / "arm.xml"), "error: " + (dir / "arm.xml").string() + ": cannot read file: Is a directory");
  const fs::path main = write(dir / "main.xml", "<mujoco>\n  <include file=\"part.xml\"/>\n</mujoco>\n");
  EXPECT_EQ(load_in_child(main),
            "error: " + main.string() + ":2: <include file>: " + (dir / "part.xml").string() + ": cannot read file: Is a directory");
}

// ---- Size caps

// A file of `bytes` zero bytes, without writing them (sparse).
fs::path sized(const fs::path& path, std::uintmax_t bytes) {
  write(path, "");
  fs::resize_file(path, bytes);
  return path;
}

TEST(InputFiles, AModelFileOrIncludePastTheModelCapIsRefused) {
  const fs::path dir = test_directory();
  const fs::path big = sized(dir / "big.xml", kMaxModelFileBytes + 1);
  EXPECT_EQ(load_in_child(big), "error: " + big.string() + ": larger than the 16 MiB a model file may be (with its includes)");
  const fs::path part = sized(dir / "part.xml", kMaxModelFileBytes + 1);
  const fs::path main = write(dir / "main.xml", "<mujoco>\n  <include file=\"part.xml\"/>\n</mujoco>\n");
  const std::string message = load_in_child(main);
  EXPECT_THAT(message, StartsWith("error: " + main.string() + ":2: <include file>: " + part.string() + ": larger than the ")) << message;
  EXPECT_THAT(message, HasSubstr(" bytes left of the 16 MiB a model file and its includes may have")) << message;
}

TEST(InputFiles, IncludesShareTheModelCap) {
  // Two includes of 9 MiB each: either alone fits, together they do not.
  const fs::path dir = test_directory();
  const std::string padding = "<mujoco>\n<!--" + std::string(9u << 20, ' ') + "-->\n</mujoco>\n";
  write(dir / "a.xml", padding);
  write(dir / "b.xml", padding);
  const fs::path one = write(dir / "one.xml", "<mujoco>\n  <include file=\"a.xml\"/>\n" + kArm.substr(9));
  EXPECT_EQ(load_in_child(one), "loaded 1 bodies");
  const fs::path two = write(dir / "two.xml", "<mujoco>\n  <include file=\"a.xml\"/>\n  <include file=\"b.xml\"/>\n</mujoco>\n");
  EXPECT_THAT(load_in_child(two), StartsWith("error: " + two.string() + ":3: <include file>: " + (dir / "b.xml").string() + ": larger than"));
  fs::remove_all(dir);  // 18 MiB
}

// ---- Nesting

TEST(InputNesting, JsonNestedTooDeepIsRefusedAtTheFirstBracketTooDeepAndNoSooner) {
  const std::string open(200'000, '[');
  for (const std::string& text : {open, open + std::string(200'000, ']')}) {
    const testing::ChildOutcome outcome = in_child([&] {
      load_scene_text(text, "deep.json");
      return std::string("loaded");
    });
    EXPECT_EQ(outcome.signal, 0) << outcome.ending();
    EXPECT_EQ(outcome.output, "error: deep.json:1:65: arrays and objects nested deeper than 64 (a scene needs at most 6)");
  }
  // At the cap, 64 levels (the root object and 63 arrays), the format refuses it, the depth check does not.
  const std::string at_cap = R"({"limber_scene": 1, "name": )" + std::string(63, '[') + std::string(63, ']') + "}";
  try {
    load_scene_text(at_cap, "cap.json");
    FAIL() << "loaded";
  } catch (const ModelError& error) {
    EXPECT_STREQ(error.what(), "cap.json: name: must be a string, got array");
  }
  const std::string in_string = R"({"limber_scene": 1, "name": ")" + std::string(100, '[') + R"(\"[", "x": 1})";
  try {
    load_scene_text(in_string, "string.json");
    FAIL() << "loaded";
  } catch (const ModelError& error) {
    EXPECT_STREQ(error.what(), "string.json: unknown field \"x\"");
  }
}

// An MJCF chain of `bodies` welded spheres, each body on its own line, its child body before
// its geom (so a body is the first element of its depth).
std::string mjcf_chain(int bodies) {
  std::string xml = "<mujoco>\n<worldbody>\n";
  for (int k = 0; k < bodies; ++k) xml += "<body name=\"b" + std::to_string(k) + "\" pos=\"0 0 -.1\">\n";
  for (int k = 0; k < bodies; ++k) xml += "<geom size=\".02\"/></body>";
  return xml + "\n</worldbody>\n</mujoco>\n";
}

TEST(InputNesting, XmlNestedTooDeepIsRefusedByName) {
  // Body bK is element K + 3 (mujoco, worldbody): b998 is the first past 1000, on line 1001;
  // link lK is element K + 2 (robot): l999.
  const fs::path dir = test_directory();
  const fs::path deep = write(dir / "deep.xml", mjcf_chain(100'000));
  EXPECT_EQ(load_in_child(deep), "error: " + deep.string() +
                                     ":1001: <body name='b998'>: nested more than 1000 elements deep (the root element the first): "
                                     "no model needs so deep a tree");
  std::string links = "<robot name=\"r\">\n";
  for (int k = 0; k < 100'000; ++k) links += "<link name=\"l" + std::to_string(k) + "\">\n";
  for (int k = 0; k < 100'000; ++k) links += "</link>";
  const fs::path robot = write(dir / "deep.urdf", links + "\n</robot>\n");
  const std::string message = load_in_child(robot);
  EXPECT_THAT(message, StartsWith("error: " + robot.string() + ":1001: <link name='l999'>: nested more than 1000 elements deep")) << message;
}

TEST(InputNesting, AnMjcfChainAtTheDepthCapLoads) {
  // 997 bodies: the deepest geom is element 1000.
  const fs::path dir = test_directory();
  EXPECT_EQ(load_in_child(write(dir / "chain.xml", mjcf_chain(997))), "loaded 997 bodies");
  EXPECT_THAT(load_in_child(write(dir / "longer.xml", mjcf_chain(998))), HasSubstr("<geom>: nested more than 1000 elements deep"));
}

TEST(InputNesting, IncludesNestedTooDeepAreRefused) {
  // 0.xml includes 1.xml at its root, which includes 2.xml, ...: each splice recurses. (Built by
  // appending: GCC 12 warns falsely, -Wrestrict, on "literal" + std::string.)
  const fs::path dir = test_directory();
  const int files = kMaxXmlDepth + 2;
  for (int k = 0; k < files; ++k) {
    std::string text = "<mujoco>\n";
    if (k + 1 < files) text.append("  <include file=\"").append(std::to_string(k + 1)).append(".xml\"/>\n");
    write(dir / std::to_string(k).append(".xml"), text.append("</mujoco>\n"));
  }
  const std::string message = load_in_child(dir / "0.xml");
  EXPECT_THAT(message, HasSubstr(":2: <include>: includes nested more than 1000 deep (through the files' roots)")) << message;
}

}  // namespace
}  // namespace limber
