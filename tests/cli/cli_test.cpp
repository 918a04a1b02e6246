// The `limber` program: the summary it prints, and one clear line for every kind of bad input.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <sys/stat.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/cli/run_cli.hpp"
#include "tests/support/test_directory.hpp"
#include "tools/cli/cli.hpp"
#include "tools/cli/output_file.hpp"
#include "tools/cli/run_flags.hpp"

namespace limber::cli {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

using test::Result;
using test::run;
using test::scene;

// The summary's verdict says the run held together: "ok", or "inaccurate: ..." (a measure passed
// its tolerance at some step), not a divergence.
::testing::AssertionResult HeldTogether(const std::string& out) {
  if (out.find("\nstatus      ok\n") != std::string::npos || out.find("\nstatus      inaccurate: ") != std::string::npos) {
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure() << "the run did not hold together:\n" << out;
}

// A bad input: exit code 2, nothing on stdout, exactly one line on stderr mentioning `needle`.
void expect_rejected(const std::vector<std::string>& arguments, const std::string& needle) {
  const Result r = run(arguments);
  EXPECT_EQ(r.code, kBadInput) << r.err;
  EXPECT_EQ(r.out, "");
  EXPECT_THAT(r.err, HasSubstr(needle));
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

TEST(Cli, DefaultRunSimulatesTheEmbeddedHumanoid) {
  const Result r = run({"run", "--steps", "300"});
  ASSERT_EQ(r.code, kSuccess) << r.err;
  EXPECT_THAT(r.out, HasSubstr("limber run: humanoid"));
  EXPECT_THAT(r.out, HasSubstr("9 limbs, 8 joints, ground, ball"));
  EXPECT_THAT(r.out, HasSubstr("joint gap"));
  EXPECT_THAT(r.out, HasSubstr("travelled"));
  EXPECT_THAT(r.out, HasSubstr("woke at t ="));
  EXPECT_TRUE(HeldTogether(r.out));
}

TEST(Cli, LimitsLineFollowsTheJointGapLine) {
  // The armed ragdoll: 12 joints with limits (no drives); its knees and elbows are held in range.
  const Result r = run({"run", scene("ragdoll.json"), "--steps", "120"});
  ASSERT_EQ(r.code, kSuccess) << r.err;
  EXPECT_THAT(r.out, HasSubstr("\nlimits      12 limited joints: largest violation "));
  EXPECT_THAT(r.out, HasSubstr(" rad in run, "));
  EXPECT_LT(r.out.find("joint gap"), r.out.find("limits      ")) << r.out;
  // The active ragdoll: its 12 drives too, limp once the ball hits.
  const Result active = run({"run", scene("active_ragdoll.json"), "--steps", "80"});
  ASSERT_EQ(active.code, kSuccess) << active.err;
  EXPECT_THAT(active.out, HasSubstr("; 12 drives: tracking error "));
  EXPECT_THAT(active.out, HasSubstr("limp since the ball hit"));
  // The chain has neither.
  const Result chain = run({"run", scene("chain.json"), "--steps", "20"});
  ASSERT_EQ(chain.code, kSuccess) << chain.err;
  EXPECT_THAT(chain.out, HasSubstr("\nlimits      none\n"));
}

// The largest joint gap in a run's summary ("joint gap ... largest in run X"), relative to a link.
double largest_joint_gap(const std::string& out) {
  const std::string key = "largest in run ";
  const std::size_t line = out.find("joint gap");
  const std::size_t at = out.find(key, line);
  return line == std::string::npos || at == std::string::npos ? -1 : std::stod(out.substr(at + key.size()));
}

TEST(Cli, JointSolveTreeHoldsTheRagdollsJointsWhereFewSweepsOfRowsLeaveThemOpen) {
  // The armed ragdoll hit by the ball, 2 substeps of 2 sweeps: its joints as rows open; solved
  // as a tree after every sweep they stay closed to rounding.
  const std::vector<std::string> few = {"run", scene("ragdoll.json"), "--steps", "240", "--substeps", "2", "--iterations", "2", "--joint-solve", "rows"};
  std::vector<std::string> tree(few.begin(), few.end() - 1);
  tree.push_back("tree");
  const Result rows_run = run(few), tree_run = run(tree);
  ASSERT_EQ(rows_run.code, kSuccess) << rows_run.err;
  ASSERT_EQ(tree_run.code, kSuccess) << tree_run.err;
  EXPECT_GT(largest_joint_gap(rows_run.out), 1e-3) << rows_run.out;
  EXPECT_GE(largest_joint_gap(tree_run.out), 0) << tree_run.out;
  EXPECT_LT(largest_joint_gap(tree_run.out), 1e-6) << tree_run.out;
  // It needs the coloured Gauss-Seidel sweep: Jacobi is refused by name.
  tree.insert(tree.end(), {"--solver", "jacobi"});
  const Result refused = run(tree);
  EXPECT_NE(refused.code, kSuccess);
  EXPECT_THAT(refused.err, HasSubstr("Gauss-Seidel"));
}

TEST(Cli, ChainRunsWithAHundredLinks) {
  const Result r = run({"run", scene("chain.json"), "--links", "100", "--steps", "20", "--precision", "float"});
  ASSERT_EQ(r.code, kSuccess) << r.err;
  EXPECT_THAT(r.out, HasSubstr("100 limbs, 100 joints"));
}

TEST(Cli, CopiesLayScenesSideBySide) {
  const Result r = run({"run", scene("chain.json"), "--copies", "3", "--steps", "10"});
  ASSERT_EQ(r.code, kSuccess) << r.err;
  EXPECT_THAT(r.out, HasSubstr("15 limbs, 15 joints"));  // 3 copies of the 5-link chain, 3 islands
  EXPECT_THAT(r.out, HasSubstr("3 islands"));
}

TEST(Cli, OutWritesOneCsvRowPerStepPlusTheStart) {
  const std::string path = (limber::testing::test_directory() / "cli_trajectory.csv").string();
  const Result r = run({"run", scene("stick_in_box.json"), "--steps", "25", "--out", path});
  ASSERT_EQ(r.code, kSuccess) << r.err;
  std::ifstream csv(path);
  std::string header, line;
  std::getline(csv, header);
  EXPECT_EQ(header, "time,stick.head_x,stick.head_y,stick.head_z,stick.tail_x,stick.tail_y,stick.tail_z");
  int rows = 0;
  while (std::getline(csv, line)) ++rows;
  EXPECT_EQ(rows, 26);
}

TEST(Cli, EverySolverPathGivesTheSameSummaryOfAChain) {
  // Layouts, lanes and threads change nothing but speed: the physics lines must be identical.
  const auto physics = [](const std::string& out) { return out.substr(out.find("joint gap")); };
  const Result reference = run({"run", scene("chain.json"), "--links", "40", "--steps", "50", "--scalar", "--threads", "1"});
  ASSERT_EQ(reference.code, 0) << reference.err;
  EXPECT_THAT(reference.out, HasSubstr("2 colours"));
  for (const std::vector<std::string>& variant :
       {std::vector<std::string>{"--layout", "aos"}, {"--layout", "aosoa", "--threads", "2"}, {"--threading", "parallel-for", "--threads", "2"}}) {
    std::vector<std::string> arguments{"run", scene("chain.json"), "--links", "40", "--steps", "50"};
    arguments.insert(arguments.end(), variant.begin(), variant.end());
    const Result r = run(arguments);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(physics(r.out), physics(reference.out)) << variant[0] << " " << variant[1];
  }
}
TEST(Cli, TheRainsFirstThirtyRagdollsRunAndLand) {
  // 30 copies: the lowest layer's first three rows, beside the stairs, fall 1 m onto the ground (0.45 s, 108 steps).
  const Result r = run({"run", scene("rain.json"), "--copies", "30", "--steps", "120", "--iterations", "20", "--joint-solve", "tree"});
  ASSERT_EQ(r.code, kSuccess) << r.err;
  EXPECT_THAT(r.out, HasSubstr("390 limbs, 360 joints"));
  EXPECT_THAT(r.out, Not(HasSubstr("contacts    0 at end")));
}

TEST(Cli, ThePileGivesTheSameTrajectoryBitsForOneOrTwoThreadsAndScalarLanes) {
  // 32 self-colliding ragdolls: by step 120 hundreds of contact rows are coloured and swept.
  const auto trajectory = [](const std::vector<std::string>& variant, const std::string& name) {
    const std::string csv = (limber::testing::test_directory() / ("pile_" + name + ".csv")).string();
    std::vector<std::string> arguments{"run", scene("ragdoll_pile.json"), "--steps", "120", "--out", csv};
    arguments.insert(arguments.end(), variant.begin(), variant.end());
    const Result r = run(arguments);
    EXPECT_EQ(r.code, kSuccess) << r.err;
    EXPECT_THAT(r.out, Not(HasSubstr("contacts    0 at end")));
    std::ostringstream text;
    text << std::ifstream(csv).rdbuf();
    return text.str();
  };
  const std::string one = trajectory({"--threads", "1"}, "one");
  ASSERT_FALSE(one.empty());
  EXPECT_EQ(one, trajectory({"--threads", "2"}, "two")) << "two threads";
  EXPECT_EQ(one, trajectory({"--threads", "1", "--scalar"}, "scalar")) << "scalar lanes";
}

TEST(Cli, RattleRunsTheChainInSubsteps) {
  const Result r = run({"run", scene("chain.json"), "--projection", "rattle", "--substeps", "16", "--steps", "60"});
  ASSERT_EQ(r.code, kSuccess) << r.err;
  EXPECT_THAT(r.out, HasSubstr("rattle projection; up to"));
  EXPECT_THAT(r.out, HasSubstr("16 substeps a step"));
  EXPECT_THAT(r.out, HasSubstr("pbd fallbacks 0"));
}

TEST(Cli, SceneRelaxationSettingsRunAsStatedAndKeepTheCsvColumns) {
  // settings.relaxation {"projection": "rattle", "substeps": 64, "iterations": 4}, with --out.
  const std::string text = R"({"limber_scene": 1, "name": "rattle chain",
    "settings": {"gravity": [0, 0, -9.81], "time_step": 0.016666666666666666, "duration": 1,
                 "relaxation": {"projection": "rattle", "substeps": 64, "iterations": 4}},
    "chain": {"links": 5, "shape": "capsule", "link_length": 0.1, "link_radius": 0.005, "link_mass": 1, "end_mass": 2,
              "anchor": [0, 0, 1], "direction": [1, 0, 0], "pinned": true}})";
  const std::string path = (limber::testing::test_directory() / "rattle_chain.json").string(), csv_path = (limber::testing::test_directory() / "rattle.csv").string();
  std::ofstream(path) << text;
  const Result r = run({"run", path, "--steps", "30", "--out", csv_path});
  ASSERT_EQ(r.code, kSuccess) << r.err;
  EXPECT_THAT(r.out, HasSubstr("rattle projection; up to 4 sweeps a substep, 64 substeps a step"));
  std::ifstream csv(csv_path);
  std::string header;
  std::getline(csv, header);
  EXPECT_THAT(header, HasSubstr("link_0.head_x,link_0.head_y,link_0.head_z"));
}

TEST(Cli, ProfilePrintsEachStageInTheOrderItRunsAfterTheSummary) {
  // Every line "profile     <stage> ...", in order, after the status line: the particle
  // method's seven stages, then the rest and the whole step; a rigid method's two.
  const auto stage_lines = [](const std::vector<std::string>& arguments, const std::vector<std::string>& stages) {
    const Result r = run(arguments);
    ASSERT_EQ(r.code, kSuccess) << r.err;
    std::size_t at = r.out.find("\nstatus      ");
    ASSERT_NE(at, std::string::npos) << r.out;
    for (const std::string& stage : stages) {
      const std::size_t next = r.out.find("\nprofile     " + stage + " ", at);
      ASSERT_NE(next, std::string::npos) << stage << " after position " << at << " in\n" << r.out;
      at = next;
    }
  };
  stage_lines({"run", "--steps", "60", "--profile"},
              {"integrate", "detect", "colour", "relax", "velocity", "restitution", "sleep", "rest", "step"});
  stage_lines({"run", scene("chain.json"), "--projection", "rattle", "--substeps", "4", "--steps", "20", "--profile"},
              {"integrate", "detect", "colour", "relax", "velocity", "restitution", "sleep", "rest", "step"});
  for (const char* method : {"springs-implicit", "lagrange", "featherstone"}) {
    stage_lines({"run", "--method", method, "--steps", "60", "--profile"}, {"integrate", "detect", "rest", "step"});
  }
  const Result plain = run({"run", "--steps", "60"});
  EXPECT_THAT(plain.out, Not(HasSubstr("profile     "))) << "without --profile";
}

TEST(Cli, RejectsBadProjectionAndSubsteps) {
  expect_rejected({"run", "--projection", "shake"}, "--projection");
  expect_rejected({"run", "--substeps", "0"}, "--substeps: must be in [1, 10000], got 0");
  expect_rejected({"run", "--method", "lagrange", "--substeps", "4"}, "--substeps");
}

// A model file: MJCF runs under the method that can represent it, its loader's notes on stderr;
// a bad one is one line naming the file, the line and the element.
TEST(Cli, RunsAnMjcfModelAndPrintsWhatItsLoaderDropped) {
  const std::filesystem::path directory = limber::testing::test_directory();
  const std::string good = (directory / "pendulum.xml").string(), bad = (directory / "bad.xml").string();
  std::ofstream(good) << "<mujoco model=\"pendulum\">\n<worldbody>\n<light pos=\"0 0 3\"/>\n<body pos=\"0 0 1\">\n"
                         "<joint name=\"pivot\" axis=\"0 1 0\"/>\n<geom type=\"capsule\" fromto=\"0 0 0 0.3 0 0\" size=\"0.02\"/>\n"
                         "</body>\n</worldbody>\n</mujoco>\n";
  std::ofstream(bad) << "<mujoco>\n<worldbody>\n<body>\n<joint type=\"screw\"/>\n</body>\n</worldbody>\n</mujoco>\n";
  const Result r = run({"run", good, "--method", "featherstone", "--steps", "50"});
  ASSERT_EQ(r.code, kSuccess) << r.err;
  EXPECT_THAT(r.out, HasSubstr("limber run: pendulum"));
  EXPECT_THAT(r.err, HasSubstr("limber: note: " + good + ":3: <light>: ignored"));
  expect_rejected({"run", bad, "--method", "featherstone"}, bad + ":4: <joint type>");
  std::filesystem::remove_all(directory);
}

// The verdict is over every step, not the end state: the ragdoll at 1/30 s under reduced
// coordinates ends at rest and closed, but on the way a shin went through the ground and a limit
// was passed by radians. Each is named with its size and time against the scene's tolerance, and
// tolerances loosened in the scene file let the same run through.
TEST(Cli, TheVerdictSeesEveryStepOfTheRun) {
  const Result coarse = run({"run", scene("ragdoll.json"), "--method", "featherstone", "--dt", "0.0333"});
  ASSERT_EQ(coarse.code, kSuccess) << coarse.err;
  EXPECT_THAT(coarse.out, HasSubstr("\nstatus      inaccurate: "));
  EXPECT_THAT(coarse.out, HasSubstr("into the ground at t = "));
  EXPECT_THAT(coarse.out, HasSubstr("a limit passed by "));

  std::ostringstream text;
  text << std::ifstream(scene("ragdoll.json")).rdbuf();
  std::string loose = text.str();
  const std::size_t settings = loose.find("\"settings\": {");
  ASSERT_NE(settings, std::string::npos);
  loose.insert(settings + 13, R"("tolerances": {"penetration": 10, "limit": 10, "joint_gap": 10, "energy_gain": 10}, )");
  const std::string path = (limber::testing::test_directory() / "loose_tolerances.json").string();
  std::ofstream(path) << loose;
  const Result forgiven = run({"run", path, "--method", "featherstone", "--dt", "0.0333"});
  ASSERT_EQ(forgiven.code, kSuccess) << forgiven.err;
  EXPECT_THAT(forgiven.out, HasSubstr("\nstatus      ok\n"));
  std::filesystem::remove(path);
}

TEST(Cli, RunsJacobiAndTheSequentialSweep) {
  for (const char* solver : {"--solver=jacobi", "--sweep=sequential"}) {
    const Result r = run({"run", scene("chain.json"), "--steps", "20", solver});
    EXPECT_EQ(r.code, 0) << r.err;
  }
}
TEST(Cli, SpringMethodsRunEveryShippedScene) {
  for (const char* method : {"springs-explicit", "springs-implicit"}) {
    for (const char* file : {"humanoid.json", "chain.json", "stick_in_box.json"}) {
      const Result r = run({"run", scene(file), "--method", method, "--steps", "200"});
      ASSERT_EQ(r.code, kSuccess) << method << " " << file << ": " << r.err;
      EXPECT_THAT(r.out, HasSubstr("rigid limbs joined by stiff springs")) << file;
      EXPECT_TRUE(HeldTogether(r.out)) << file;
    }
  }
  const Result r = run({"run", "--method", "springs-explicit", "--integrator", "rk4", "--stiffness", "3e4", "--damping", "40", "--steps", "50"});
  ASSERT_EQ(r.code, kSuccess) << r.err;
  EXPECT_THAT(r.out, HasSubstr("RK4"));
  EXPECT_THAT(r.out, HasSubstr("stiffness 30000 N/m, damping 40 N s/m"));
}

TEST(Cli, SpringsWriteHeadAndTailColumns) {
  const std::string path = (limber::testing::test_directory() / "springs.csv").string();
  const Result r = run({"run", scene("chain.json"), "--method", "springs-implicit", "--steps", "5", "--out", path});
  ASSERT_EQ(r.code, kSuccess) << r.err;
  std::ifstream csv(path);
  std::string header;
  std::getline(csv, header);
  EXPECT_THAT(header, HasSubstr("link_0.head_x"));
  EXPECT_EQ(std::count(header.begin(), header.end(), ','), 3 * 2 * 5);
}

TEST(Cli, LagrangeRunsEveryShippedScene) {
  for (const char* stabilization : {"baumgarte", "projection"}) {
    for (const char* file : {"humanoid.json", "chain.json", "stick_in_box.json", "gears.json"}) {
      const Result r = run({"run", scene(file), "--method", "lagrange", "--stabilization", stabilization, "--steps", "200"});
      ASSERT_EQ(r.code, kSuccess) << stabilization << " " << file << ": " << r.err;
      EXPECT_THAT(r.out, HasSubstr("rigid limbs and joint constraints")) << file;
      EXPECT_TRUE(HeldTogether(r.out)) << file;
    }
  }
}

TEST(Cli, OnlyLagrangeRunsGears) {
  // Every method takes the axles' hinges now; only Lagrange takes the gear.
  expect_rejected({"run", scene("gears.json"), "--method", "weighted"}, "gears[0] 'mesh': the ");
  expect_rejected({"run", scene("gears.json"), "--method", "springs-implicit"}, "gears[0] 'mesh': the ");
}

TEST(Cli, RejectsLagrangeFlagsElsewhere) { expect_rejected({"run", "--constraint-solver", "tree"}, "--constraint-solver"); }
TEST(Cli, RejectsSpringFlagsWithLagrange) { expect_rejected({"run", "--method", "lagrange", "--damping", "3"}, "--damping"); }

TEST(Cli, RejectsVerletFlagsWithSprings) { expect_rejected({"run", "--method", "springs-explicit", "--sweep", "sequential"}, "--sweep"); }
TEST(Cli, RejectsSpringFlagsWithVerlet) { expect_rejected({"run", "--stiffness", "1e5"}, "--stiffness"); }
TEST(Cli, RejectsFloatSprings) { expect_rejected({"run", "--method", "springs-implicit", "--precision", "float"}, "double"); }
TEST(Cli, RejectsExplicitIntegratorWithImplicitSprings) {
  expect_rejected({"run", "--method", "springs-implicit", "--integrator", "rk4"}, "backward-euler");
}
TEST(Cli, RejectsNegativeStiffness) { expect_rejected({"run", "--method", "springs-explicit", "--stiffness", "-5"}, "--stiffness: must be in (0, 1e12]"); }

TEST(Cli, RejectsSequentialJacobi) { expect_rejected({"run", "--sweep", "sequential", "--solver", "jacobi"}, "--sweep"); }
TEST(Cli, RejectsUnknownLayout) { expect_rejected({"run", "--layout", "soaos"}, "soaos"); }
TEST(Cli, RejectsNegativeThreads) { expect_rejected({"run", "--threads", "-2"}, "--threads"); }
TEST(Cli, RejectsUnknownFlag) { expect_rejected({"run", "--speed", "3"}, "--speed"); }
TEST(Cli, RejectsUnknownMethod) { expect_rejected({"run", "--method", "midpoint"}, "midpoint"); }
TEST(Cli, RejectsMissingSubcommand) { expect_rejected({}, "subcommand"); }
TEST(Cli, RejectsNonPositiveTimeStep) { expect_rejected({"run", "--dt", "0"}, "--dt: must be in [1e-09, 1]"); }
TEST(Cli, RejectsNotANumberTimeStep) { expect_rejected({"run", "--dt", "nan"}, "--dt"); }
TEST(Cli, RejectsZeroIterations) { expect_rejected({"run", "--iterations", "0"}, "--iterations: must be in [1, 100000]"); }
TEST(Cli, RejectsNegativeBallMass) { expect_rejected({"run", "--ball-mass", "-1"}, "--ball-mass: must be in (0, 1e9]"); }
TEST(Cli, RejectsInfiniteBallSpeed) { expect_rejected({"run", "--ball-speed", "inf"}, "--ball-speed"); }
TEST(Cli, RejectsRestitutionAboveOne) { expect_rejected({"run", "--ball-restitution", "1.5"}, "--ball-restitution"); }
TEST(Cli, RejectsZeroBallDirection) { expect_rejected({"run", "--ball-direction", "0,0,0"}, "--ball-direction"); }
TEST(Cli, RejectsShortBallDirection) { expect_rejected({"run", "--ball-direction", "1,0"}, "--ball-direction"); }
TEST(Cli, RejectsNegativeFriction) { expect_rejected({"run", "--friction", "-0.1"}, "--friction: must be in [0, 100]"); }
TEST(Cli, RejectsFrictionWithoutGround) { expect_rejected({"run", scene("chain.json"), "--friction", "0.3"}, "no ground"); }
TEST(Cli, RejectsBallFlagsWithoutBall) { expect_rejected({"run", scene("chain.json"), "--ball-speed", "3"}, "no ball"); }
TEST(Cli, RejectsUnknownBodyVariant) { expect_rejected({"run", "--body", "giant"}, "giant"); }
TEST(Cli, RejectsLinksOnASceneWithoutChain) { expect_rejected({"run", "--links", "10"}, "chain"); }
TEST(Cli, RejectsZeroCopies) { expect_rejected({"run", scene("chain.json"), "--copies", "0"}, "copies.count"); }
TEST(Cli, RejectsZeroSteps) { expect_rejected({"run", "--steps", "0"}, "--steps"); }
TEST(Cli, RejectsMissingSceneFile) { expect_rejected({"run", "no/such/scene.json"}, "no/such/scene.json"); }

// Every numeric flag turns away NaN, infinity, negatives and values past its stated limit, each
// with one line naming the flag (the limits keep a slip of the keyboard from running for days).
TEST(Cli, EveryNumericFlagRejectsNanInfNegativesAndValuesPastItsLimit) {
  struct Case {
    std::vector<std::string> context;  // the scene and flags the flag needs
    std::string flag;
    std::vector<std::string> values;
  };
  const std::vector<std::string> none, chain{scene("chain.json")}, direct{"--solver", "direct"}, springs{"--method", "springs-explicit"};
  const std::vector<Case> cases{
      {none, "--dt", {"nan", "inf", "-1", "0", "2", "1e-300", "5e-10"}},
      {none, "--steps", {"-1", "0", "2000000000"}},
      {none, "--iterations", {"-3", "0", "200000"}},
      {none, "--substeps", {"-1", "0", "20000"}},
      {none, "--threads", {"-1", "100000"}},
      {none, "--ball-speed", {"nan", "inf", "-1", "1e6"}},
      {none, "--ball-radius", {"nan", "inf", "-1", "0", "1e300", "1001"}},
      {none, "--ball-mass", {"nan", "inf", "-1", "0", "1e300"}},
      {none, "--ball-restitution", {"nan", "inf", "-0.1", "1.5"}},
      {none, "--friction", {"nan", "inf", "-1", "1e300"}},
      {none, "--tolerance", {"nan", "inf", "-1", "1e300"}},
      {none, "--budget-us", {"nan", "inf", "-1", "1e300"}},
      {none, "--over-relaxation", {"nan", "inf", "-1", "0", "2"}},
      {chain, "--links", {"-1", "0", "1000000000000"}},
      {chain, "--copies", {"-1", "0", "1000000000"}},
      {springs, "--stiffness", {"nan", "inf", "-1", "0", "1e300"}},
      {springs, "--damping", {"nan", "inf", "-1", "1e300"}},
      {direct, "--newton-iterations", {"-1", "0", "1000000"}},
      {direct, "--compliance", {"nan", "inf", "-1", "1e300"}},
  };
  for (const Case& c : cases) {
    for (const std::string& value : c.values) {
      std::vector<std::string> arguments{"run"};
      arguments.insert(arguments.end(), c.context.begin(), c.context.end());
      arguments.insert(arguments.end(), {c.flag, value, "--steps", "1"});
      if (c.flag == "--steps") arguments.resize(arguments.size() - 2);
      SCOPED_TRACE(c.flag + " " + value);
      const std::string needle = c.flag == "--links" || c.flag == "--copies" ? "" : c.flag;  // scene options name the field
      expect_rejected(arguments, needle);
    }
  }
}

// "ok" means ok: a run that holds together but opens its joints past a percent of a link, or
// gains energy, is flagged (exit code still 0); a converged one is not, and the energy line
// gives the drift against the scene's energy scale.
TEST(Cli, AnOkRunThatOpensItsJointsOrGainsEnergyIsFlagged) {
  const Result poor = run({"run", scene("chain.json"), "--links", "1000", "--projection", "rattle", "--substeps", "8", "--steps", "240"});
  ASSERT_EQ(poor.code, kSuccess) << poor.out;
  EXPECT_THAT(poor.out, ::testing::ContainsRegex("status      inaccurate: (joint '[^']+' open|joints open \\(or links stretched\\)) by "));
  const Result good = run({"run", scene("chain.json"), "--steps", "240"});
  ASSERT_EQ(good.code, kSuccess) << good.out;
  EXPECT_THAT(good.out, HasSubstr("\nstatus      ok\n"));
  EXPECT_THAT(good.out, HasSubstr("of the scene's energy scale ("));
}

// A chain on springs too soft to hold it comes apart: the run says so and exits 1, though no
// number is infinite and no point is fast.
TEST(Cli, AJointComeApartIsADivergenceAndExitsOne) {
  const Result r = run({"run", scene("chain.json"), "--method", "springs-explicit", "--stiffness", "1", "--steps", "2000"});
  EXPECT_EQ(r.code, kDiverged) << r.out;
  EXPECT_THAT(r.out, HasSubstr("DIVERGED (a joint gap or a link's stretch past a whole link)"));
}

// A scene path that is no scene file: one line naming it, whatever it is.
TEST(Cli, WhatIsNoSceneFileGetsOneLineNamingIt) {
  const std::string directory = (limber::testing::test_directory() / "cli_directory").string();
  std::filesystem::create_directories(directory);
  expect_rejected({"run", directory}, directory);
  const std::string empty = (limber::testing::test_directory() / "cli_empty.json").string();
  std::ofstream(empty).flush();
  expect_rejected({"run", empty}, "empty file");
  const std::string garbage = (limber::testing::test_directory() / "cli_garbage.json").string();
  std::ofstream(garbage, std::ios::binary) << std::string("\x00\xff\x13{[\"", 6);
  expect_rejected({"run", garbage}, garbage);
  const std::string huge = (limber::testing::test_directory() / "cli_huge.json").string();
  std::ofstream(huge).flush();
  std::filesystem::resize_file(huge, std::uintmax_t(65) << 20);  // sparse: 65 MiB of zeros
  expect_rejected({"run", huge}, "MiB");
  std::filesystem::remove(huge);
}

// --out never writes over the scene, however the path is spelled, and leaves it as it was.
TEST(Cli, OutNeverWritesOverTheSceneFile) {
  const std::string copy = (limber::testing::test_directory() / "cli_scene_copy.json").string();
  std::filesystem::copy_file(scene("chain.json"), copy, std::filesystem::copy_options::overwrite_existing);
  const auto bytes = [](const std::string& path) {
    std::ostringstream text;
    text << std::ifstream(path, std::ios::binary).rdbuf();
    return text.str();
  };
  const std::string before = bytes(copy);
  const std::string respelled = std::filesystem::path(copy).parent_path().string() + "/./" + std::filesystem::path(copy).filename().string();
  expect_rejected({"run", copy, "--steps", "2", "--out", respelled}, "--out");
  EXPECT_EQ(bytes(copy), before);
  expect_rejected({"run", copy, "--steps", "2", "--out", limber::testing::test_directory().string()}, "directory");
}

// --out replaces only a regular file: a device, a pipe or a socket at its path is refused
// before the run and stays what it was; /dev/null and /dev/full included (as root, a rename
// would replace the device node itself). Whatever is at NAME.part is no concern of the run's:
// it writes a temporary file of its own.
TEST(Cli, OutRefusesToReplaceAnythingButARegularFile) {
  const std::filesystem::path folder = limber::testing::test_directory();
  const std::string pipe = (folder / "pipe").string();
  ASSERT_EQ(mkfifo(pipe.c_str(), 0600), 0);
  for (const std::string& path : {std::string("/dev/null"), std::string("/dev/full"), pipe}) {
    SCOPED_TRACE(path);
    const std::filesystem::file_type before = std::filesystem::symlink_status(path).type();
    expect_rejected({"run", scene("chain.json"), "--steps", "2", "--out", path}, "not a regular file");
    expect_rejected({"view", scene("chain.json"), "--frames", "1", "--screenshot", path}, "not a regular file");
    EXPECT_EQ(std::filesystem::symlink_status(path).type(), before);
    EXPECT_THAT(test::partial_files(std::filesystem::path(path).parent_path()), ::testing::IsEmpty());
  }
  const std::string beside = (folder / "out.csv").string();
  ASSERT_EQ(mkfifo((beside + ".part").c_str(), 0600), 0);
  const Result r = run({"run", scene("chain.json"), "--steps", "2", "--out", beside});
  EXPECT_EQ(r.code, kSuccess) << r.err;
  EXPECT_EQ(std::filesystem::symlink_status(beside + ".part").type(), std::filesystem::file_type::fifo);
  EXPECT_TRUE(std::filesystem::is_regular_file(beside));
  std::filesystem::remove_all(folder);
}

// A symbolic link at --out is followed: the file it names gets the trajectory and the link
// stays a link; a link to a device or to nothing is refused.
TEST(Cli, OutWritesThroughASymbolicLinkAndKeepsIt) {
  const std::filesystem::path folder = limber::testing::test_directory();
  const std::filesystem::path target = folder / "results.csv", link = folder / "latest.csv";
  std::ofstream(target) << "an older result\n";
  std::filesystem::create_symlink(target, link);
  const Result r = run({"run", scene("chain.json"), "--steps", "2", "--out", link.string()});
  ASSERT_EQ(r.code, kSuccess) << r.err;
  EXPECT_TRUE(std::filesystem::is_symlink(link));
  std::ifstream written(target);
  std::string header;
  std::getline(written, header);
  EXPECT_THAT(header, HasSubstr("time"));
  std::filesystem::create_symlink("/dev/null", folder / "null.csv");
  expect_rejected({"run", scene("chain.json"), "--steps", "2", "--out", (folder / "null.csv").string()}, "not a regular file");
  std::filesystem::create_symlink(folder / "nowhere" / "x.csv", folder / "dangling.csv");
  expect_rejected({"run", scene("chain.json"), "--steps", "2", "--out", (folder / "dangling.csv").string()}, "link to nothing");
  std::filesystem::remove_all(folder);
}

// A trajectory that could not fit on the disk (10⁹ rows of 10⁴ links: petabytes) is refused
// before the run, and leaves no file.
TEST(Cli, OutRefusesATrajectoryLargerThanTheFreeSpace) {
  const std::filesystem::path folder = limber::testing::test_directory();
  const std::string path = (folder / "huge.csv").string();
  expect_rejected({"run", scene("chain.json"), "--links", "10000", "--steps", "1000000000", "--out", path}, "free in");
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_THAT(test::partial_files(folder), ::testing::IsEmpty());
  std::filesystem::remove_all(folder);
}

// A scene whose bodies would not fit in the memory available is refused before they are
// generated, with one line naming the file, the field and both figures; what fits passes.
TEST(Cli, RefusesBodiesThatNeedMoreMemoryThanIsAvailable) {
  RunFlags flags;
  flags.method = "featherstone";
  const double gigabyte = 1e9;
  try {
    require_memory_for(1e7, "chain.json", "chain.links", flags, gigabyte);
    ADD_FAILURE() << "10^7 bodies accepted in 1 GB";
  } catch (const OutOfMemoryError& error) {
    const std::string message = error.what();
    EXPECT_THAT(message, HasSubstr("chain.json: chain.links: 1e+07 bodies need about "));
    EXPECT_THAT(message, HasSubstr("under featherstone"));
    EXPECT_THAT(message, HasSubstr("more than the 1 GB of memory available"));
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
  EXPECT_NO_THROW(require_memory_for(1e4, "chain.json", "chain.links", flags, gigabyte));
  // Each method's estimate is its own, the rigid ones' larger than the particles' per body.
  RunFlags particles;
  EXPECT_LT(bytes_per_body(particles), bytes_per_body(flags));
}

// An output file appears under its name only once complete: an abandoned one leaves nothing,
// not even over an older file of that name.
TEST(Cli, AnOutputFileAppearsOnlyWhenComplete) {
  const std::string path = (limber::testing::test_directory() / "cli_output.csv").string();
  std::ofstream(path) << "an older result\n";
  std::filesystem::path partial;
  {
    OutputFile file(path, "--out", {});
    partial = file.partial_path();
    EXPECT_TRUE(std::filesystem::is_regular_file(partial)) << partial;
    file.stream() << "half a trajectory";
  }  // abandoned: not committed
  std::ifstream older(path);
  std::string line;
  std::getline(older, line);
  EXPECT_EQ(line, "an older result");
  EXPECT_FALSE(std::filesystem::exists(partial)) << partial;
  {
    OutputFile file(path, "--out", {});
    partial = file.partial_path();
    file.stream() << "complete\n";
    file.commit();
  }
  std::ifstream done(path);
  std::getline(done, line);
  EXPECT_EQ(line, "complete");
  EXPECT_FALSE(std::filesystem::exists(partial)) << partial;
}

// The README's example of an error runs as written and prints the line the README shows.
TEST(Cli, TheReadmesErrorExamplePrintsWhatTheReadmeShows) {
  std::ifstream readme(std::string(LIMBER_SOURCE_DIR) + "/README.md");
  std::string line, command, shown;
  while (std::getline(readme, line)) {
    if (line.rfind("$ limber run ", 0) == 0) {
      command = line.substr(2);
      std::getline(readme, shown);
      break;
    }
  }
  ASSERT_FALSE(command.empty()) << "README.md shows no '$ limber run' example";
  std::vector<std::string> arguments;
  std::istringstream words(command.substr(std::string("limber ").size()));
  for (std::string word; words >> word;) arguments.push_back(word);
  const std::filesystem::path here = std::filesystem::current_path();
  std::filesystem::current_path(LIMBER_SOURCE_DIR);  // the README's paths are the repository's
  const Result r = run(arguments);
  std::filesystem::current_path(here);
  EXPECT_EQ(r.code, kBadInput);
  EXPECT_EQ(r.err, shown + "\n");
}

TEST(Cli, RejectsABadSceneFileNamingFileAndField) {
  const std::string path = (limber::testing::test_directory() / "cli_bad_scene.json").string();
  std::ifstream in(scene("chain.json"));
  std::stringstream text;
  text << in.rdbuf();
  std::string json = text.str();
  const auto at = json.find("\"link_mass\"");
  ASSERT_NE(at, std::string::npos);
  json.replace(at, std::string("\"link_mass\"").size(), "\"link_mass\": -1, \"unused\"");
  std::ofstream(path) << json;
  const Result r = run({"run", path});
  EXPECT_EQ(r.code, kBadInput);
  EXPECT_THAT(r.err, HasSubstr(path));
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

// --version says the version the project declares (CMakeLists.txt's project()), not a copy of it.
TEST(Cli, VersionIsTheProjectsDeclaredVersion) {
  std::ifstream lists(std::string(LIMBER_SOURCE_DIR) + "/CMakeLists.txt");
  std::string line, declared;
  while (std::getline(lists, line) && declared.empty()) {
    const std::size_t at = line.find("project(limber VERSION ");
    if (at != std::string::npos) declared = line.substr(at + 23, line.find(' ', at + 23) - (at + 23));
  }
  ASSERT_FALSE(declared.empty());
  const Result r = run({"--version"});
  EXPECT_EQ(r.code, kSuccess);
  EXPECT_EQ(r.out, "limber " + declared + "\n");
}

TEST(Cli, HelpExitsCleanly) {
  const Result r = run({"run", "--help"});
  EXPECT_EQ(r.code, kSuccess);
  EXPECT_THAT(r.out, HasSubstr("--ball-speed"));
  EXPECT_THAT(r.err, Not(HasSubstr("limber:")));
}

TEST(Cli, FeatherstoneRunsTheShippedScenesAndRefusesWhatReducedCoordinatesCannotExpress) {
  for (const char* file : {"humanoid.json", "chain.json", "stick_in_box.json"}) {
    const Result r = run({"run", scene(file), "--method", "featherstone", "--steps", "240"});
    ASSERT_EQ(r.code, kSuccess) << file << ": " << r.err;
    EXPECT_THAT(r.out, HasSubstr("method      featherstone: rigid limbs in reduced coordinates")) << file;
    EXPECT_THAT(r.out, HasSubstr("RK4")) << file;
    EXPECT_THAT(r.out, HasSubstr("\nstatus      ok\n")) << file;  // reduced coordinates: exact joints, no limit passed
  }
  const Result humanoid = run({"run", "--method", "featherstone", "--integrator", "semi-implicit", "--steps", "10"});
  ASSERT_EQ(humanoid.code, kSuccess) << humanoid.err;
  EXPECT_THAT(humanoid.out, HasSubstr("semi-implicit Euler"));
  EXPECT_THAT(humanoid.out, HasSubstr("tree        10 bodies, 36 degrees of freedom (nv; nq 46), 2 floating roots: head, ball"));
  EXPECT_THAT(humanoid.out, HasSubstr("joint gap"));
  expect_rejected({"run", scene("gears.json"), "--method", "featherstone"}, "gears[0] 'mesh': the featherstone method does not support gears");
  for (const char* integrator : {"euler", "rk2", "backward-euler"}) {
    expect_rejected({"run", "--method", "featherstone", "--integrator", integrator},
                    std::string("--integrator ") + integrator + ": featherstone takes semi-implicit or rk4");
  }
  expect_rejected({"run", "--method", "featherstone", "--iterations", "5"}, "--iterations: applies to the Verlet methods");
  expect_rejected({"run", "--method", "featherstone", "--stiffness", "5"}, "--stiffness: applies to the spring methods");
  expect_rejected({"run", "--method", "featherstone", "--stabilization", "projection"}, "--stabilization: applies to lagrange");
  expect_rejected({"run", "--method", "featherstone", "--precision", "float"}, "double only");
}

}  // namespace
}  // namespace limber::cli
