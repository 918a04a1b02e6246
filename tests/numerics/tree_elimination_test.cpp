// TreeElimination (kernel/numerics/tree_elimination.hpp): Baraff's elimination of a tree-shaped
// saddle-point system [M Jᵀ; J −A]·[x; μ] = [f; c] agrees with a dense solve of the same system
// to rounding, for rigid bodies (6 × 6 blocks) and particles (3 × 3), constraints of 1 to 6 rows,
// rigid and compliant; and in SIMD lanes, each lane its own system of the same shape, every
// lane gives the bits the number-valued elimination gives on that lane's system.
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>
#include <xsimd/xsimd.hpp>

#include "limber/kernel/numerics/tree_elimination.hpp"

namespace limber {
namespace {

constexpr int kBodies = 9;

// One system's numbers: per body its M block (symmetric positive definite) and f; per
// constraint its J blocks on its bodies (rows × B), its compliance (diagonal, ≥ 0) and c.
template <int B>
struct System {
  std::vector<Eigen::Matrix<double, B, B>> mass;
  std::vector<Eigen::Matrix<double, B, 1>> force;
  std::vector<Eigen::Matrix<double, B, B>> on_inboard, on_outboard;
  std::vector<Eigen::Matrix<double, B, 1>> compliance, value;
};

// The shape shared by every lane: constraint c joins body inboard[c] (−1: the world) to body
// c + 1 (a random tree rooted at body 0, plus a constraint holding body 0 to the world).
struct Shape {
  std::vector<std::int32_t> inboard, outboard;
  std::vector<std::uint8_t> rows;
};

template <int B>
Shape random_shape(std::mt19937& random) {
  Shape shape;
  shape.inboard.push_back(-1), shape.outboard.push_back(0);
  for (int body = 1; body < kBodies; ++body) {
    shape.inboard.push_back(std::uniform_int_distribution<int>(0, body - 1)(random));
    shape.outboard.push_back(body);
  }
  for (std::size_t c = 0; c < shape.inboard.size(); ++c) {
    shape.rows.push_back(static_cast<std::uint8_t>(1 + c % B));  // every row count 1…B
  }
  return shape;
}

template <int B>
System<B> random_system(const Shape& shape, std::mt19937& random) {
  std::uniform_real_distribution<double> entry(-1, 1);
  const auto matrix = [&] { return Eigen::Matrix<double, B, B>(Eigen::Matrix<double, B, B>::NullaryExpr([&] { return entry(random); })); };
  const auto vector = [&] { return Eigen::Matrix<double, B, 1>(Eigen::Matrix<double, B, 1>::NullaryExpr([&] { return entry(random); })); };
  System<B> system;
  for (int body = 0; body < kBodies; ++body) {
    const Eigen::Matrix<double, B, B> root = matrix();
    // Masses from 1 to 1000: the mass ratios a ragdoll brings.
    const double scale = std::pow(10.0, 3 * (entry(random) + 1) / 2);
    system.mass.push_back(scale * (root * root.transpose() + Eigen::Matrix<double, B, B>::Identity()));
    system.force.push_back(vector());
  }
  for (std::size_t c = 0; c < shape.inboard.size(); ++c) {
    // As a joint's: the outboard body's block near [E …] (its anchor moves with it), the
    // inboard's anything (an anchor on a lever, a limit's axis).
    system.on_inboard.push_back(matrix());
    system.on_outboard.push_back(Eigen::Matrix<double, B, B>::Identity() + 0.3 * matrix());
    Eigen::Matrix<double, B, 1> compliance = Eigen::Matrix<double, B, 1>::Zero();
    if (c % 2 == 1) compliance = vector().cwiseAbs() * 1e-3;  // every other constraint compliant
    system.compliance.push_back(compliance), system.value.push_back(vector());
  }
  return system;
}

// The whole saddle-point matrix and right-hand side, dense.
template <int B>
std::pair<Eigen::MatrixXd, Eigen::VectorXd> dense_system(const Shape& shape, const System<B>& system) {
  int rows = 0;
  std::vector<int> offset;
  for (const std::uint8_t r : shape.rows) offset.push_back(kBodies * B + rows), rows += r;
  const int n = kBodies * B + rows;
  Eigen::MatrixXd kkt = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd right(n);
  for (int body = 0; body < kBodies; ++body) {
    kkt.block<B, B>(body * B, body * B) = system.mass[static_cast<std::size_t>(body)];
    right.segment<B>(body * B) = system.force[static_cast<std::size_t>(body)];
  }
  for (std::size_t c = 0; c < shape.rows.size(); ++c) {
    const int m = shape.rows[c], at = offset[c];
    for (const auto& [body, jacobian] : {std::pair{shape.inboard[c], &system.on_inboard[c]}, std::pair{shape.outboard[c], &system.on_outboard[c]}}) {
      if (body < 0) continue;
      kkt.block(at, body * B, m, B) = jacobian->topRows(m);
      kkt.block(body * B, at, B, m) = jacobian->topRows(m).transpose();
    }
    kkt.block(at, at, m, m) = -Eigen::MatrixXd(system.compliance[c].head(m).asDiagonal());
    right.segment(at, m) = system.value[c].head(m);
  }
  return {kkt, right};
}

// Loads lane `lane` of the elimination's inputs from `system`.
template <typename Value, int B>
void load(TreeElimination<Value, B>& elimination, const Shape& shape, const System<B>& system, std::size_t lane) {
  for (int body = 0; body < kBodies; ++body) {
    for (int i = 0; i < B; ++i) {
      for (int j = 0; j < B; ++j) set_lane(elimination.diagonal(body)(i, j), lane, system.mass[static_cast<std::size_t>(body)](i, j));
      set_lane(elimination.work(body)(i, 0), lane, system.force[static_cast<std::size_t>(body)](i));
    }
  }
  for (std::size_t c = 0; c < shape.rows.size(); ++c) {
    const std::size_t node = kBodies + c;
    for (int i = 0; i < B; ++i) {
      for (int j = 0; j < B; ++j) set_lane(elimination.diagonal(node)(i, j), lane, i == j ? -system.compliance[c](i) : 0.0);
      set_lane(elimination.work(node)(i, 0), lane, system.value[c](i));
    }
  }
}

template <typename Value, int B>
TreeElimination<Value, B> prepared(const Shape& shape) {
  TreeElimination<Value, B> elimination;
  elimination.assign(order_tree(kBodies, shape.inboard, shape.outboard), kBodies, shape.rows);
  return elimination;
}

// The J blocks of lanes: edge(constraint, body).
template <typename Value, int B>
std::vector<std::array<Block<Value, B, B>, 2>> edges(const Shape& shape, const std::vector<System<B>>& lanes) {
  std::vector<std::array<Block<Value, B, B>, 2>> blocks(shape.rows.size());
  for (std::size_t c = 0; c < shape.rows.size(); ++c) {
    for (std::size_t lane = 0; lane < lanes.size(); ++lane) {
      for (int i = 0; i < B; ++i) {
        for (int j = 0; j < B; ++j) {
          set_lane(blocks[c][0](i, j), lane, lanes[lane].on_inboard[c](i, j));
          set_lane(blocks[c][1](i, j), lane, lanes[lane].on_outboard[c](i, j));
        }
      }
    }
  }
  return blocks;
}

template <typename Value, int B>
void eliminate(TreeElimination<Value, B>& elimination, const Shape& shape, const std::vector<System<B>>& lanes) {
  const auto blocks = edges<Value, B>(shape, lanes);
  const TreeOrdering& ordering = elimination.ordering();
  ASSERT_EQ(ordering.components.size(), 1u);
  const bool definite = elimination.eliminate(ordering.components[0].begin, ordering.components[0].end,
                                              [&](std::size_t c, std::int32_t body) -> const Block<Value, B, B>& {
                                                return blocks[c][shape.outboard[c] == body ? 1 : 0];
                                              });
  EXPECT_TRUE(definite);
}

// Calls visit(shape, system, elimination, trial) for 20 random systems, each factored and solved.
template <int B, typename Visit>
void for_random_systems(unsigned seed, Visit&& visit) {
  std::mt19937 random(seed);
  for (int trial = 0; trial < 20; ++trial) {
    const Shape shape = random_shape<B>(random);
    const System<B> system = random_system<B>(shape, random);
    TreeElimination<double, B> elimination = prepared<double, B>(shape);
    load(elimination, shape, system, 0);
    eliminate(elimination, shape, {system});
    visit(shape, system, elimination, trial);
  }
}

template <int B>
void expect_agrees_with_dense_solve() {
  for_random_systems<B>(7 + B, [](const Shape& shape, const System<B>& system, const TreeElimination<double, B>& elimination, int trial) {
    const auto [kkt, right] = dense_system(shape, system);
    const Eigen::VectorXd expected = kkt.partialPivLu().solve(right);
    Eigen::VectorXd got(expected.size());
    int at = 0;
    for (int body = 0; body < kBodies; ++body, at += B) got.segment<B>(at) = elimination.work(body);
    for (std::size_t c = 0; c < shape.rows.size(); at += shape.rows[c], ++c) {
      got.segment(at, shape.rows[c]) = elimination.work(kBodies + c).head(shape.rows[c]);
    }
    // The systems' condition numbers are 10⁶–10⁸ (masses 1 to 1000): 1e-9 is rounding times that.
    EXPECT_LT((got - expected).norm(), 1e-9 * expected.norm()) << "B = " << B << ", trial " << trial;
  });
}

TEST(TreeElimination, AgreesWithADenseSolveOfTheWholeSystem) {
  expect_agrees_with_dense_solve<3>();
  expect_agrees_with_dense_solve<6>();
}

// inverse_diagonal(): each body's block of the inverse of the whole saddle-point matrix (its
// mobility with every constraint kept) agrees with the dense inverse's.
// solve_nodes() on the paths from two loaded bodies to the root gives, at those bodies, the bits
// solve() gives over the whole tree for the same loads (the other nodes only add zeros).
template <int B>
void expect_path_solves_to_match_whole_solves() {
  for_random_systems<B>(17 + B, [](const Shape&, const System<B>& system, TreeElimination<double, B>& elimination, int trial) {
    std::mt19937 random(static_cast<unsigned>(trial));
    std::uniform_int_distribution<std::int32_t> pick(0, kBodies - 1);
    const std::array<std::int32_t, 2> loaded{pick(random), pick(random)};
    const TreeOrdering::Component& whole = elimination.ordering().components[0];
    const auto load = [&] {
      for (std::size_t s = 0; s < 2; ++s) elimination.work(static_cast<std::size_t>(loaded[s])) += system.force[s];
    };
    for (std::size_t node = 0; node < elimination.node_count(); ++node) elimination.work(node).setZero();
    load();
    elimination.solve(whole.begin, whole.end);
    const std::array<Eigen::Matrix<double, B, 1>, 2> expected{elimination.work(static_cast<std::size_t>(loaded[0])),
                                                              elimination.work(static_cast<std::size_t>(loaded[1]))};
    std::vector<std::int32_t> room(elimination.node_count());
    const std::size_t count = elimination.path_to_root(loaded, room);
    EXPECT_LE(count, elimination.node_count());
    const std::span<const std::int32_t> path(room.data(), count);
    for (const std::int32_t node : path) elimination.work(static_cast<std::size_t>(node)).setConstant(7.0);  // stale values
    for (const std::int32_t node : path) elimination.work(static_cast<std::size_t>(node)).setZero();
    load();
    elimination.solve_nodes(path);
    for (std::size_t s = 0; s < 2; ++s) {
      for (int i = 0; i < B; ++i) {
        EXPECT_EQ(elimination.work(static_cast<std::size_t>(loaded[s]))(i), expected[s](i)) << "B = " << B << ", trial " << trial << ", body " << loaded[s];
      }
    }
  });
}

TEST(TreeElimination, APathSolveGivesTheLoadedBodiesTheWholeSolvesBits) {
  expect_path_solves_to_match_whole_solves<3>();
  expect_path_solves_to_match_whole_solves<6>();
}

template <int B>
void expect_body_blocks_of_the_inverse() {
  for_random_systems<B>(13 + B, [](const Shape& shape, const System<B>& system, TreeElimination<double, B>& elimination, int trial) {
    elimination.inverse_diagonal(elimination.ordering().components[0].begin, elimination.ordering().components[0].end);
    const Eigen::MatrixXd inverse = dense_system(shape, system).first.inverse();
    for (int body = 0; body < kBodies; ++body) {
      const Eigen::Matrix<double, B, B> expected = inverse.block<B, B>(body * B, body * B);
      const Eigen::Matrix<double, B, B> got = elimination.mobility(static_cast<std::size_t>(body));
      EXPECT_LT((got - expected).norm(), 1e-9 * inverse.norm()) << "B = " << B << ", trial " << trial << ", body " << body;
    }
  });
}

TEST(TreeElimination, InverseDiagonalGivesEachBodysBlockOfTheInverse) {
  expect_body_blocks_of_the_inverse<3>();
  expect_body_blocks_of_the_inverse<6>();
}

template <int B>
void expect_lanes_give_each_systems_bits() {
  using Lanes = xsimd::batch<double>;
  constexpr std::size_t width = Lanes::size;
  std::mt19937 random(11 + B);
  for (int trial = 0; trial < 5; ++trial) {
    const Shape shape = random_shape<B>(random);
    std::vector<System<B>> systems;
    for (std::size_t lane = 0; lane < width; ++lane) systems.push_back(random_system<B>(shape, random));
    TreeElimination<Lanes, B> lanes = prepared<Lanes, B>(shape);
    for (std::size_t lane = 0; lane < width; ++lane) load(lanes, shape, systems[lane], lane);
    eliminate(lanes, shape, systems);
    for (std::size_t lane = 0; lane < width; ++lane) {
      TreeElimination<double, B> one = prepared<double, B>(shape);
      load(one, shape, systems[lane], 0);
      eliminate(one, shape, {systems[lane]});
      for (std::size_t node = 0; node < one.node_count(); ++node) {
        for (int i = 0; i < B; ++i) {
          // Bit for bit (EXPECT_EQ on doubles is exact).
          EXPECT_EQ(get_lane(lanes.work(node)(i, 0), lane), one.work(node)(i)) << "B = " << B << ", lane " << lane << ", node " << node;
        }
      }
    }
  }
}

TEST(TreeElimination, EachSimdLaneGivesTheBitsOfItsOwnSystemSolvedAlone) {
  expect_lanes_give_each_systems_bits<3>();
  expect_lanes_give_each_systems_bits<6>();
}

}  // namespace
}  // namespace limber
