// ConstraintElimination (kernel/numerics/constraint_elimination.hpp): the constraint-space solve
// of (J W Jᵀ + α̃) μ = r over a tree of particles gives, to rounding, the multipliers of a dense
// solve and of the body–constraint elimination (TreeElimination over 3 × 3 particle blocks), on
// chains, branching trees and stars, rigid and compliant, with masses 1 to 1000 kg, of distance
// constraints (one row) and zero-length joints (three); a factor serves many right-hand sides;
// a particle with too many rows is refused; instances of one shape solved side by side in SIMD
// lanes give each instance's own bits.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>
#include <xsimd/xsimd.hpp>

#include "limber/kernel/numerics/constraint_elimination.hpp"
#include "limber/kernel/numerics/lane_blocks.hpp"
#include "limber/kernel/numerics/tree_elimination.hpp"

namespace limber {
namespace {

using Vector3d = Eigen::Vector3d;

// A tree of particles: constraint c joins body_i[c] and body_j[c] (−1: the world), with its
// rows (1: J = ±nᵀ with its direction n; 3: J = ±E), compliance α̃ and right-hand side r (its
// rows' entries in order, rows of all constraints concatenated); each particle's weight w (1/kg).
struct Tree {
  std::vector<std::int32_t> body_i, body_j;
  std::vector<std::uint8_t> rows;
  std::vector<Vector3d> direction;
  std::vector<double> compliance, right, weight;
  std::vector<int> offset;  // per constraint: its first row
};

// `parent(k)` gives particle k's inboard particle (k ≥ 1); particle 0 hangs from the world when
// `pinned`. Each constraint's sides are drawn in either order, so both signs occur; with
// `joints`, about a third of the constraints are zero-length joints of three rows.
template <typename Parent>
Tree random_tree(int particles, Parent&& parent, bool pinned, bool compliant, std::mt19937& random, bool joints = false) {
  std::uniform_real_distribution<double> unit(-1, 1), fraction(0, 1);
  Tree tree;
  int total = 0;
  const auto add = [&](std::int32_t a, std::int32_t b) {
    if (fraction(random) < 0.5) std::swap(a, b);
    tree.body_i.push_back(a), tree.body_j.push_back(b);
    const std::uint8_t rows = joints && fraction(random) < 0.33 ? 3 : 1;
    tree.rows.push_back(rows), tree.offset.push_back(total), total += rows;
    tree.direction.push_back(Vector3d(unit(random), unit(random), unit(random)).normalized());
    tree.compliance.push_back(compliant ? 1e-3 * fraction(random) : 0.0);
    for (int r = 0; r < rows; ++r) tree.right.push_back(unit(random));
  };
  if (pinned) add(-1, 0);
  for (int k = 1; k < particles; ++k) add(parent(k), k);
  for (int k = 0; k < particles; ++k) tree.weight.push_back(1 / std::pow(10.0, 3 * fraction(random)));  // 1 to 1000 kg
  return tree;
}

// A constraint's J block on one side (rows × 3): ±nᵀ or ±E.
Eigen::MatrixXd block(const Tree& tree, std::size_t c, double sign) {
  if (tree.rows[c] == 3) return sign * Eigen::Matrix3d::Identity();
  return sign * tree.direction[c].transpose();
}

// J W Jᵀ + α̃, dense.
Eigen::MatrixXd dense_matrix(const Tree& tree) {
  const auto rows = static_cast<int>(tree.right.size());
  Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(rows, 3 * static_cast<int>(tree.weight.size()));
  Eigen::VectorXd compliance(rows);
  for (std::size_t c = 0; c < tree.body_i.size(); ++c) {
    const int at = tree.offset[c], m = tree.rows[c];
    if (tree.body_i[c] >= 0) jacobian.block(at, 3 * tree.body_i[c], m, 3) = block(tree, c, 1);
    if (tree.body_j[c] >= 0) jacobian.block(at, 3 * tree.body_j[c], m, 3) = block(tree, c, -1);
    compliance.segment(at, m).setConstant(tree.compliance[c]);
  }
  Eigen::VectorXd weights(3 * tree.weight.size());
  for (std::size_t k = 0; k < tree.weight.size(); ++k) weights.segment<3>(3 * static_cast<int>(k)).setConstant(tree.weight[k]);
  Eigen::MatrixXd matrix = jacobian * weights.asDiagonal() * jacobian.transpose();
  matrix.diagonal() += compliance;
  return matrix;
}

std::vector<std::int32_t> inboard_of(const Tree& tree) {
  std::vector<std::int32_t> inboard = tree.body_i, outboard = tree.body_j;
  for (std::size_t c = 0; c < inboard.size(); ++c) {
    if (outboard[c] < 0) std::swap(inboard[c], outboard[c]);
  }
  return inboard;
}
std::vector<std::int32_t> outboard_of(const Tree& tree) {
  std::vector<std::int32_t> outboard = tree.body_j;
  for (std::size_t c = 0; c < outboard.size(); ++c) {
    if (outboard[c] < 0) outboard[c] = tree.body_i[c];
  }
  return outboard;
}

// The multipliers of the constraint-space solve, one component (the whole tree).
Eigen::VectorXd constraint_space(const Tree& tree, ConstraintElimination<double>& elimination, bool& definite) {
  const TreeOrdering ordering = order_tree(tree.weight.size(), inboard_of(tree), outboard_of(tree));
  EXPECT_EQ(ordering.components.size(), 1u);
  EXPECT_TRUE(ordering.loop_constraints.empty());
  elimination.assign(ordering, tree.weight.size(), tree.body_i, tree.body_j, tree.rows);
  EXPECT_TRUE(elimination.solvable(0));
  definite = elimination.factor(
      0, [&](std::size_t body) { return tree.weight[body]; }, [&](std::size_t c) -> const Vector3d& { return tree.direction[c]; },
      [&](std::size_t c) { return tree.compliance[c]; });
  Eigen::VectorXd mu(static_cast<int>(tree.right.size()));
  for (std::size_t c = 0; c < tree.rows.size(); ++c) {
    for (int r = 0; r < tree.rows[c]; ++r) elimination.multiplier(c, r) = tree.right[static_cast<std::size_t>(tree.offset[c] + r)];
  }
  elimination.solve(0);
  for (std::size_t c = 0; c < tree.rows.size(); ++c) {
    for (int r = 0; r < tree.rows[c]; ++r) mu[tree.offset[c] + r] = elimination.multiplier(c, r);
  }
  return mu;
}

// The same multipliers from the body–constraint form, [W⁻¹ Jᵀ; J −α̃][x; ν] = [0; −r]: ν = μ.
Eigen::VectorXd particle_blocks(const Tree& tree) {
  TreeElimination<double, 3> elimination;
  const std::vector<std::int32_t> inboard = inboard_of(tree), outboard = outboard_of(tree);
  elimination.assign(order_tree(tree.weight.size(), inboard, outboard), tree.weight.size(), tree.rows);
  const auto bodies = static_cast<std::int32_t>(tree.weight.size());
  for (std::int32_t body = 0; body < bodies; ++body) {
    elimination.diagonal(static_cast<std::size_t>(body)) = Eigen::Matrix3d::Identity() / tree.weight[static_cast<std::size_t>(body)];
    elimination.work(static_cast<std::size_t>(body)).setZero();
  }
  for (std::size_t c = 0; c < tree.rows.size(); ++c) {
    elimination.diagonal(static_cast<std::size_t>(bodies) + c) = -tree.compliance[c] * Eigen::Matrix3d::Identity();
    Vector3d right = Vector3d::Zero();
    for (int r = 0; r < tree.rows[c]; ++r) right[r] = -tree.right[static_cast<std::size_t>(tree.offset[c] + r)];
    elimination.work(static_cast<std::size_t>(bodies) + c) = right;
  }
  const auto edge = [&](std::size_t c, std::int32_t body) {
    Eigen::Matrix3d padded = Eigen::Matrix3d::Zero();
    padded.topRows(tree.rows[c]) = block(tree, c, tree.body_i[c] == body ? 1.0 : -1.0);
    return padded;
  };
  const auto& components = elimination.ordering().components;
  EXPECT_TRUE(elimination.eliminate(components[0].begin, components[0].end, edge));
  Eigen::VectorXd mu(static_cast<int>(tree.right.size()));
  for (std::size_t c = 0; c < tree.rows.size(); ++c) {
    for (int r = 0; r < tree.rows[c]; ++r) mu[tree.offset[c] + r] = elimination.work(static_cast<std::size_t>(bodies) + c)[r];
  }
  return mu;
}

void expect_agreement(const Tree& tree) {
  ConstraintElimination<double> elimination;
  bool definite = false;
  const Eigen::VectorXd mu = constraint_space(tree, elimination, definite);
  EXPECT_TRUE(definite);
  const Eigen::VectorXd right = Eigen::Map<const Eigen::VectorXd>(tree.right.data(), static_cast<int>(tree.right.size()));
  const Eigen::MatrixXd matrix = dense_matrix(tree);
  const Eigen::VectorXd dense = matrix.ldlt().solve(right);
  EXPECT_LE((mu - dense).norm(), 1e-12 * dense.norm()) << "against the dense solve";
  EXPECT_LE((matrix * mu - right).norm(), 1e-12 * right.norm()) << "the residual";
  const Eigen::VectorXd blocks = particle_blocks(tree);
  // The particle blocks' own error (their 3 × 3 inverses at mass ratios to 1000) reaches a few
  // 1e-12 on the longest chains: the two agree to 1e-12 beyond it.
  EXPECT_LE((mu - blocks).norm(), 1e-12 * blocks.norm() + (blocks - dense).norm()) << "against the particle blocks";
}

TEST(ConstraintElimination, ChainsGiveTheMultipliersOfADenseSolveAndOfTheParticleBlocks) {
  std::mt19937 random(11);
  for (int trial = 0; trial < 20; ++trial) {
    SCOPED_TRACE(trial);
    expect_agreement(random_tree(2 + trial * 5, [](int k) { return k - 1; }, trial % 2 == 0, trial % 3 == 0, random));
  }
}

TEST(ConstraintElimination, BranchingTreesGiveTheSameMultipliers) {
  std::mt19937 random(12);
  for (int trial = 0; trial < 40; ++trial) {
    SCOPED_TRACE(trial);
    // Each particle hangs from one of the last four: fronts of up to 5–8 constraints.
    std::mt19937 shape(static_cast<unsigned>(trial));
    const auto parent = [&](int k) { return std::uniform_int_distribution<int>(std::max(0, k - 4), k - 1)(shape); };
    expect_agreement(random_tree(3 + trial, parent, trial % 2 == 0, trial % 4 < 2, random));
  }
}

TEST(ConstraintElimination, TreesWithZeroLengthJointsGiveTheSameMultipliers) {
  std::mt19937 random(16);
  for (int trial = 0; trial < 40; ++trial) {
    SCOPED_TRACE(trial);
    std::mt19937 shape(static_cast<unsigned>(trial));
    // Chains, then trees whose particles hang from one of the last three: fronts of up to
    // 4 constraints, some of three rows.
    const auto parent = [&](int k) { return trial < 10 ? k - 1 : std::uniform_int_distribution<int>(std::max(0, k - 3), k - 1)(shape); };
    expect_agreement(random_tree(3 + trial, parent, trial % 2 == 0, trial % 4 < 2, random, true));
  }
}

TEST(ConstraintElimination, AStarAtTheLimitIsSolvedAndOneBeyondItIsRefused) {
  std::mt19937 random(13);
  const int limit = ConstraintElimination<double>::kMaxFrontRows;
  // A free hub with `limit` one-row spokes: its front holds them all.
  expect_agreement(random_tree(limit + 1, [](int) { return 0; }, false, false, random));
  const Tree beyond = random_tree(limit + 2, [](int) { return 0; }, false, false, random);
  ConstraintElimination<double> elimination;
  elimination.assign(order_tree(beyond.weight.size(), inboard_of(beyond), outboard_of(beyond)), beyond.weight.size(), beyond.body_i,
                     beyond.body_j, beyond.rows);
  EXPECT_FALSE(elimination.solvable(0));
}

TEST(ConstraintElimination, AFactorServesManyRightHandSides) {
  std::mt19937 random(14);
  Tree tree = random_tree(30, [](int k) { return k / 2; }, true, true, random, true);
  ConstraintElimination<double> elimination;
  bool definite = false;
  constraint_space(tree, elimination, definite);
  const Eigen::MatrixXd matrix = dense_matrix(tree);
  std::uniform_real_distribution<double> unit(-1, 1);
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::VectorXd right(static_cast<int>(tree.right.size()));
    for (std::size_t c = 0; c < tree.rows.size(); ++c) {
      for (int r = 0; r < tree.rows[c]; ++r) elimination.multiplier(c, r) = right[tree.offset[c] + r] = unit(random);
    }
    elimination.solve(0);
    Eigen::VectorXd mu(right.size());
    for (std::size_t c = 0; c < tree.rows.size(); ++c) {
      for (int r = 0; r < tree.rows[c]; ++r) mu[tree.offset[c] + r] = elimination.multiplier(c, r);
    }
    EXPECT_LE((matrix * mu - right).norm(), 1e-9 * right.norm());
  }
}

TEST(ConstraintElimination, AWeightlessChainIsNotDefinite) {
  std::mt19937 random(15);
  Tree tree = random_tree(5, [](int k) { return k - 1; }, false, false, random);
  for (double& w : tree.weight) w = 0;
  ConstraintElimination<double> elimination;
  bool definite = true;
  constraint_space(tree, elimination, definite);
  EXPECT_FALSE(definite);
}

// New values (directions, compliances, weights, right-hand sides) on the same shape.
Tree redraw_values(Tree tree, std::mt19937& random) {
  std::uniform_real_distribution<double> unit(-1, 1), fraction(0, 1);
  for (Vector3d& n : tree.direction) n = Vector3d(unit(random), unit(random), unit(random)).normalized();
  for (double& alpha : tree.compliance) alpha = alpha > 0 ? 1e-3 * fraction(random) : 0.0;
  for (double& r : tree.right) r = unit(random);
  for (double& w : tree.weight) w = 1 / std::pow(10.0, 3 * fraction(random));
  return tree;
}

// Each instance solved alone in Number, then all in lanes of Number (one instance a lane):
// lane k's multipliers must be instance k's bits.
template <typename Number>
void expect_lanes_give_each_instance_its_bits(const std::vector<Tree>& instances) {
  using Lanes = xsimd::batch<Number>;
  using Vector3n = Eigen::Matrix<Number, 3, 1>;
  ASSERT_EQ(instances.size(), Lanes::size);
  const Tree& shape = instances[0];
  const TreeOrdering ordering = order_tree(shape.weight.size(), inboard_of(shape), outboard_of(shape));
  const std::size_t constraints = shape.rows.size();
  std::vector<std::vector<Number>> alone(instances.size());
  for (std::size_t k = 0; k < instances.size(); ++k) {
    const Tree& tree = instances[k];
    std::vector<Vector3n> direction;
    for (const Vector3d& n : tree.direction) direction.push_back(n.cast<Number>());
    ConstraintElimination<Number> elimination;
    elimination.assign(ordering, tree.weight.size(), tree.body_i, tree.body_j, tree.rows);
    ASSERT_TRUE(elimination.factor(
        0, [&](std::size_t body) { return static_cast<Number>(tree.weight[body]); },
        [&](std::size_t c) -> const Vector3n& { return direction[c]; }, [&](std::size_t c) { return static_cast<Number>(tree.compliance[c]); }));
    for (std::size_t c = 0; c < constraints; ++c) {
      for (int r = 0; r < tree.rows[c]; ++r) elimination.multiplier(c, r) = static_cast<Number>(tree.right[static_cast<std::size_t>(tree.offset[c] + r)]);
    }
    elimination.solve(0);
    for (std::size_t c = 0; c < constraints; ++c) {
      for (int r = 0; r < tree.rows[c]; ++r) alone[k].push_back(elimination.multiplier(c, r));
    }
  }
  // The lanes: lane k of every value is instance k's.
  const auto gather = [&](auto&& value) {
    Lanes lanes(Number(0));
    for (std::size_t k = 0; k < instances.size(); ++k) set_lane(lanes, k, static_cast<Number>(value(instances[k])));
    return lanes;
  };
  std::vector<Block<Lanes, 3, 1>> direction(constraints);
  for (std::size_t c = 0; c < constraints; ++c) {
    for (int a = 0; a < 3; ++a) direction[c](a, 0) = gather([&](const Tree& tree) { return tree.direction[c][a]; });
  }
  ConstraintElimination<Lanes> lanes;
  lanes.assign(ordering, shape.weight.size(), shape.body_i, shape.body_j, shape.rows);
  ASSERT_TRUE(lanes.factor(
      0, [&](std::size_t body) { return gather([&](const Tree& tree) { return tree.weight[body]; }); },
      [&](std::size_t c) -> const Block<Lanes, 3, 1>& { return direction[c]; },
      [&](std::size_t c) { return gather([&](const Tree& tree) { return tree.compliance[c]; }); }));
  for (std::size_t c = 0; c < constraints; ++c) {
    for (int r = 0; r < shape.rows[c]; ++r) {
      lanes.multiplier(c, r) = gather([&](const Tree& tree) { return tree.right[static_cast<std::size_t>(tree.offset[c] + r)]; });
    }
  }
  lanes.solve(0);
  for (std::size_t k = 0; k < instances.size(); ++k) {
    std::size_t row = 0;
    for (std::size_t c = 0; c < constraints; ++c) {
      for (int r = 0; r < shape.rows[c]; ++r, ++row) {
        const Number mu = get_lane(lanes.multiplier(c, r), k);
        ASSERT_EQ(std::memcmp(&mu, &alone[k][row], sizeof(Number)), 0) << "instance " << k << ", constraint " << c << ", row " << r;
      }
    }
  }
}

TEST(ConstraintElimination, InstancesInLanesGiveEachInstanceItsOwnBits) {
  std::mt19937 random(17);
  for (int trial = 0; trial < 12; ++trial) {
    SCOPED_TRACE(trial);
    std::mt19937 shape_random(static_cast<unsigned>(trial));
    // Ropes, then branching trees with zero-length joints; pinned or free, rigid or compliant.
    const auto parent = [&](int k) { return trial < 4 ? k - 1 : std::uniform_int_distribution<int>(std::max(0, k - 3), k - 1)(shape_random); };
    const Tree shape = random_tree(5 + 7 * trial, parent, trial % 2 == 0, trial % 3 == 0, random, trial >= 4);
    for (const bool single : {false, true}) {
      std::vector<Tree> instances;
      const std::size_t width = single ? xsimd::batch<float>::size : xsimd::batch<double>::size;
      for (std::size_t k = 0; k < width; ++k) instances.push_back(redraw_values(shape, random));
      if (single) {
        expect_lanes_give_each_instance_its_bits<float>(instances);
      } else {
        expect_lanes_give_each_instance_its_bits<double>(instances);
      }
    }
  }
}

}  // namespace
}  // namespace limber
