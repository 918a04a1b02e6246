// `limber run --out`'s trajectory (tools/cli/trajectory.hpp) for every scene and model file,
// under every method that loads it: a named column for every field, a row for every step, each
// as long as the header — serial joints' virtual links included — or one line refusing it.
#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/cli/run_cli.hpp"
#include "tests/support/test_directory.hpp"
#include "tools/cli/cli.hpp"

namespace limber::cli {
namespace {

using ::testing::HasSubstr;
using ::testing::IsEmpty;
using ::testing::Not;
using test::Result;
using test::run;

const std::vector<std::string> kMethods{"weighted", "unweighted", "springs-explicit", "springs-implicit", "lagrange", "featherstone"};
constexpr int kSteps = 2;

std::vector<std::string> fields(const std::string& line) {
  std::vector<std::string> out(1);
  for (const char c : line) {
    if (c == ',') out.emplace_back();
    else out.back().push_back(c);
  }
  return out;
}

// The header names every column "<point>_x,<point>_y,<point>_z", every point once and by a name
// (not "", not led by a '.', as an unnamed body's "<body>.head" would be); each of the `rows`
// rows has as many fields as the header, each a number.
void expect_named_trajectory(const std::filesystem::path& csv_path, int expected_rows) {
  std::ifstream csv(csv_path);
  std::string line;
  ASSERT_TRUE(std::getline(csv, line)) << csv_path << " is empty";
  const std::vector<std::string> header = fields(line);
  ASSERT_GE(header.size(), 4u) << line;
  EXPECT_EQ(header[0], "time");
  ASSERT_EQ((header.size() - 1) % 3, 0u) << line;
  std::set<std::string> points;
  for (std::size_t c = 1; c + 2 < header.size(); c += 3) {
    const std::string point = header[c].substr(0, header[c].size() - 2);
    EXPECT_EQ(header[c], point + "_x") << "column " << c;
    EXPECT_EQ(header[c + 1], point + "_y") << "column " << c + 1;
    EXPECT_EQ(header[c + 2], point + "_z") << "column " << c + 2;
    EXPECT_FALSE(point.empty() || point.front() == '.' || point.front() == '_') << "column " << c << " has no name: '" << header[c] << "'";
    EXPECT_TRUE(points.insert(point).second) << "two points named '" << point << "'";
  }
  int rows = 0;
  while (std::getline(csv, line)) {
    ++rows;
    const std::vector<std::string> row = fields(line);
    ASSERT_EQ(row.size(), header.size()) << "row " << rows;
    for (const std::string& field : row) {
      char* end = nullptr;
      std::strtod(field.c_str(), &end);
      ASSERT_TRUE(!field.empty() && *end == '\0') << "row " << rows << ": '" << field << "'";
    }
  }
  EXPECT_EQ(rows, expected_rows);
}

// The steps a run took, from its summary's "run         N steps of ...".
int steps_done(const std::string& summary) {
  const std::size_t at = summary.find("\nrun         ");
  return at == std::string::npos ? -1 : std::stoi(summary.substr(at + 13));
}

// Runs `file` for kSteps under every method with --out into `folder`: each run writes a
// trajectory as above, or is refused with one line (exit 2) and leaves no file. Returns the
// methods that refused it.
std::vector<std::string> run_under_every_method(const std::string& file, const std::filesystem::path& folder) {
  std::vector<std::string> refused;
  for (const std::string& method : kMethods) {
    SCOPED_TRACE(file + " under " + method);
    const std::filesystem::path csv = folder / (method + ".csv");
    std::filesystem::remove(csv);  // the previous file's
    const Result r = run({"run", file, "--method", method, "--steps", std::to_string(kSteps), "--out", csv.string()});
    if (r.code == kBadInput) {  // one line after the loader's notes
      std::istringstream lines(r.err);
      std::vector<std::string> errors;
      for (std::string line; std::getline(lines, line);) {
        if (line.rfind("limber: note: ", 0) != 0) errors.push_back(line);
      }
      EXPECT_EQ(errors.size(), 1u) << r.err;
      for (const std::string& error : errors) {
        EXPECT_EQ(error.rfind("limber: ", 0), 0u) << r.err;
        EXPECT_THAT(error, Not(HasSubstr("unexpected error")));
      }
      EXPECT_FALSE(std::filesystem::exists(csv));
      refused.push_back(method);
    } else {
      // Never 3, "out of memory", for a few bodies. A run that diverges (exit 1: the active
      // ragdoll's stiff drives on the explicit springs) keeps its trajectory up to the divergence.
      EXPECT_TRUE(r.code == kSuccess || r.code == kDiverged) << r.code << ": " << r.err;
      if (r.code == kSuccess || r.code == kDiverged) expect_named_trajectory(csv, r.code == kSuccess ? kSteps + 1 : steps_done(r.out) + 1);
    }
    EXPECT_THAT(test::partial_files(folder), IsEmpty());
  }
  return refused;
}

TEST(Trajectory, EveryShippedSceneUnderEveryMethodNamesEveryColumn) {
  const std::filesystem::path folder = limber::testing::test_directory();
  int loaded = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(LIMBER_SOURCE_DIR) + "/tools/scenes")) {
    if (entry.path().extension() != ".json") continue;
    loaded += run_under_every_method(entry.path().string(), folder).size() < kMethods.size();
  }
  EXPECT_GE(loaded, 10);
  std::filesystem::remove_all(folder);
}

// Every MJCF file MuJoCo ships (Debian: libmujoco-samples), recursively. The loader refuses 13
// of the 18, by name (mocap bodies, composites, fluid forces, mesh geoms, muscles, a fromto in
// a default class); the 5 humanoids load under the weighted particles, Lagrange and Featherstone.
TEST(Trajectory, EveryMujocoModelUnderEveryMethodNamesEveryColumn) {
  const std::filesystem::path models = "/usr/share/mujoco/model";
  if (!std::filesystem::is_directory(models)) GTEST_SKIP() << models << " is not installed (libmujoco-samples)";
  const std::filesystem::path folder = limber::testing::test_directory();
  int files = 0, loaded = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(models)) {
    if (entry.path().extension() != ".xml") continue;
    ++files;
    loaded += run_under_every_method(entry.path().string(), folder).size() < kMethods.size();
  }
  EXPECT_GT(files, 0);
  EXPECT_GE(loaded, 5);
  std::filesystem::remove_all(folder);
}

// The smallest case: one body on two hinges runs them through a virtual link under the particle
// method and Lagrange, whose columns are named as the link it is; Featherstone has none.
TEST(Trajectory, ABodyOnTwoHingesNamesItsVirtualLinksColumns) {
  const std::filesystem::path folder = limber::testing::test_directory();
  const std::string model = (folder / "two_hinges.xml").string();
  std::ofstream(model) << "<mujoco model=\"two hinges\">\n<worldbody>\n<body name=\"arm\" pos=\"0 0 1\">\n"
                          "<joint name=\"pitch\" axis=\"0 1 0\"/>\n<joint name=\"roll\" axis=\"1 0 0\"/>\n"
                          "<geom type=\"capsule\" fromto=\"0 0 0 0.3 0 0\" size=\"0.02\"/>\n</body>\n</worldbody>\n</mujoco>\n";
  // The unweighted rule takes no hinges; the spring methods no serial joints.
  EXPECT_THAT(run_under_every_method(model, folder), ::testing::ElementsAre("unweighted", "springs-explicit", "springs-implicit"));
  const auto header = [&](const std::string& method) {
    std::ifstream csv(folder / (method + ".csv"));
    std::string line;
    std::getline(csv, line);
    return line + ",";
  };
  EXPECT_THAT(header("weighted"), HasSubstr(",arm.head_x,"));
  EXPECT_THAT(header("weighted"), HasSubstr(",pitch+roll/link0.head_x,"));
  EXPECT_THAT(header("lagrange"), ::testing::StartsWith("time,arm.head_x,arm.head_y,arm.head_z,arm.tail_x,arm.tail_y,arm.tail_z,"
                                                        "pitch+roll/link0.head_x,"));
  EXPECT_EQ(header("featherstone"), "time,arm.head_x,arm.head_y,arm.head_z,arm.tail_x,arm.tail_y,arm.tail_z,");  // no virtual links
  std::filesystem::remove_all(folder);
}

}  // namespace
}  // namespace limber::cli
