// Finite-difference checks of the spring force and its Jacobians, and of the whole model's
// forces against its potential energy.
#include <gtest/gtest.h>

#include <random>

#include <Eigen/Eigenvalues>

#include "drape/core/forces.h"
#include "drape/core/integrator.h"
#include "drape/core/scene.h"

using namespace drape;

namespace {

constexpr Scalar STEP = 1e-6;  // central differences: error O(STEP^2) relative

Vec3 random_vec(std::mt19937_64& rng, Scalar scale) {
  std::uniform_real_distribution<Scalar> u(-scale, scale);
  return Vec3(u(rng), u(rng), u(rng));
}

}  // namespace

TEST(SpringForce, ForceIsMinusTheEnergyGradient) {
  std::mt19937_64 rng(1);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 xi = random_vec(rng, 1), xj = random_vec(rng, 1);
    const Scalar rest = std::uniform_real_distribution<Scalar>(0.2, 2.0)(rng);
    const Scalar k = 50;
    const SpringEvaluation e = evaluate_spring(xi, xj, Vec3::Zero(), Vec3::Zero(), rest, k, 0);
    for (int c = 0; c < 3; ++c) {
      Vec3 plus = xi, minus = xi;
      plus[c] += STEP;
      minus[c] -= STEP;
      const Scalar dE = (evaluate_spring(plus, xj, Vec3::Zero(), Vec3::Zero(), rest, k, 0).energy -
                         evaluate_spring(minus, xj, Vec3::Zero(), Vec3::Zero(), rest, k, 0).energy) /
                        (2 * STEP);
      EXPECT_NEAR(e.force[c], -dE, 1e-6 * (1 + std::abs(dE)));
    }
  }
}

TEST(SpringForce, StiffnessMatchesFiniteDifferencesInTension) {
  std::mt19937_64 rng(2);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 xj = random_vec(rng, 1);
    const Vec3 direction = random_vec(rng, 1).normalized();
    const Scalar rest = 0.5;
    const Vec3 xi = xj + direction * rest * std::uniform_real_distribution<Scalar>(1.01, 2.0)(rng);  // stretched
    const SpringEvaluation e = evaluate_spring(xi, xj, Vec3::Zero(), Vec3::Zero(), rest, 80, 0);
    for (int c = 0; c < 3; ++c) {
      Vec3 plus = xi, minus = xi;
      plus[c] += STEP;
      minus[c] -= STEP;
      const Vec3 column = (evaluate_spring(plus, xj, Vec3::Zero(), Vec3::Zero(), rest, 80, 0).force -
                           evaluate_spring(minus, xj, Vec3::Zero(), Vec3::Zero(), rest, 80, 0).force) /
                          (2 * STEP);
      EXPECT_LT((e.d_force_d_x.col(c) - column).norm(), 1e-5 * (1 + column.norm()));
    }
  }
}

// A material's `compression` c scales the spring's constant in compression only: the energy
// 1/2 c k (l - L)^2 there (its force still minus its gradient, its Jacobian along the spring
// c times the linear one's), the linear spring's in tension.
TEST(SpringForce, ACompressionBelowOneSoftensOnlyACompressedSpring) {
  std::mt19937_64 rng(4);
  const Scalar rest = 0.5, k = 80, c = 0.25;
  for (int trial = 0; trial < 100; ++trial) {
    const Vec3 xj = random_vec(rng, 1), direction = random_vec(rng, 1).normalized();
    for (const Scalar ratio : {0.6, 0.95, 1.05, 1.6}) {  // compressed, then stretched
      const Vec3 xi = xj + direction * rest * ratio;
      const SpringEvaluation soft = evaluate_spring(xi, xj, Vec3::Zero(), Vec3::Zero(), rest, k, 0, c);
      const SpringEvaluation linear = evaluate_spring(xi, xj, Vec3::Zero(), Vec3::Zero(), rest, k, 0);
      const Scalar expected = ratio < 1 ? c : 1;
      EXPECT_NEAR(soft.energy, expected * linear.energy, 1e-12 * linear.energy) << ratio;
      EXPECT_LT((soft.force - expected * linear.force).norm(), 1e-12 * linear.force.norm()) << ratio;
      EXPECT_LT((soft.d_force_d_x - expected * linear.d_force_d_x).norm(), 1e-12 * linear.d_force_d_x.norm()) << ratio;
      for (int axis = 0; axis < 3; ++axis) {
        Vec3 plus = xi, minus = xi;
        plus[axis] += STEP;
        minus[axis] -= STEP;
        const Scalar dE = (evaluate_spring(plus, xj, Vec3::Zero(), Vec3::Zero(), rest, k, 0, c).energy -
                           evaluate_spring(minus, xj, Vec3::Zero(), Vec3::Zero(), rest, k, 0, c).energy) /
                          (2 * STEP);
        EXPECT_NEAR(soft.force[axis], -dE, 1e-6 * (1 + std::abs(dE))) << ratio;
      }
    }
  }
}

TEST(SpringForce, CompressionDropsOnlyTheIndefiniteTerm) {
  // In compression the exact Jacobian is -k [d d^T + (1 - L/l)(I - d d^T)] with (1 - L/l) < 0;
  // drape keeps -k d d^T (Choi and Ko 2002): the difference from finite differences must be
  // exactly the dropped term, and the kept matrix negative semi-definite.
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 100; ++trial) {
    const Vec3 xj = random_vec(rng, 1);
    const Vec3 d = random_vec(rng, 1).normalized();
    const Scalar rest = 0.5, k = 80;
    const Scalar length = rest * std::uniform_real_distribution<Scalar>(0.3, 0.95)(rng);
    const Vec3 xi = xj + d * length;
    const SpringEvaluation e = evaluate_spring(xi, xj, Vec3::Zero(), Vec3::Zero(), rest, k, 0);
    Mat3 fd;
    for (int c = 0; c < 3; ++c) {
      Vec3 plus = xi, minus = xi;
      plus[c] += STEP;
      minus[c] -= STEP;
      fd.col(c) = (evaluate_spring(plus, xj, Vec3::Zero(), Vec3::Zero(), rest, k, 0).force -
                   evaluate_spring(minus, xj, Vec3::Zero(), Vec3::Zero(), rest, k, 0).force) /
                  (2 * STEP);
    }
    const Mat3 dropped = -k * (1 - rest / length) * (Mat3::Identity() - d * d.transpose());
    EXPECT_LT((fd - e.d_force_d_x - dropped).norm(), 1e-4 * (1 + fd.norm()));
    const Eigen::SelfAdjointEigenSolver<Mat3> eig(e.d_force_d_x);
    EXPECT_LE(eig.eigenvalues().maxCoeff(), 1e-9);
  }
}

TEST(SpringForce, DampingJacobianMatchesFiniteDifferences) {
  std::mt19937_64 rng(4);
  for (int trial = 0; trial < 100; ++trial) {
    const Vec3 xi = random_vec(rng, 1), xj = random_vec(rng, 1), vi = random_vec(rng, 2), vj = random_vec(rng, 2);
    const SpringEvaluation e = evaluate_spring(xi, xj, vi, vj, 0.7, 30, 0.4);
    for (int c = 0; c < 3; ++c) {
      Vec3 plus = vi, minus = vi;
      plus[c] += STEP;
      minus[c] -= STEP;
      const Vec3 column = (evaluate_spring(xi, xj, plus, vj, 0.7, 30, 0.4).force -
                           evaluate_spring(xi, xj, minus, vj, 0.7, 30, 0.4).force) /
                          (2 * STEP);
      EXPECT_LT((e.d_force_d_v.col(c) - column).norm(), 1e-6 * (1 + column.norm()));
    }
  }
}

TEST(ModelForces, PotentialEnergyGradientMatchesTheSpringsAndHinges) {
  // Perturbed grids, with bend springs, with bending hinges and with springs soft in
  // compression: the sum of the springs' and hinges' forces must be minus the gradient of
  // potential_energy.
  for (const char* material : {"{}", R"({"bending_rigidity": 0.01})", R"({"compression": 0.2})"}) {
    Scene scene = parse_scene(R"({"cloths": [{"grid": {"size": [1, 1], "resolution": [4, 3]}, "material": )" +
                                  std::string(material) + R"(}], "gravity": [0, 0, 0]})",
                              "inline.json");
    const Model model = build_model(scene);
    State state = initial_state(model);
    std::mt19937_64 rng(5);
    for (Vec3& x : state.positions) x += random_vec(rng, 0.05);
    std::vector<Vec3> force(model.vertex_count(), Vec3::Zero());
    for (const Spring& s : model.springs) {
      const auto e = evaluate_spring(state.positions[s.i], state.positions[s.j], Vec3::Zero(), Vec3::Zero(),
                                     s.rest_length, s.stiffness, 0, s.compression);
      force[s.i] += e.force;
      force[s.j] -= e.force;
    }
    const std::vector<Vec3> still(model.vertex_count(), Vec3::Zero());
    for (const Hinge& hinge : model.hinges)
      for (std::size_t i = 0; i < 4; ++i) force[std::size_t(hinge.v[i])] += hinge_force(hinge, i, state.positions, still);
    for (std::size_t v = 0; v < model.vertex_count(); ++v) {
      for (int c = 0; c < 3; ++c) {
        State plus = state, minus = state;
        plus.positions[v][c] += STEP;
        minus.positions[v][c] -= STEP;
        const Scalar dE = (potential_energy(model, plus) - potential_energy(model, minus)) / (2 * STEP);
        EXPECT_NEAR(force[v][c], -dE, 1e-5 * (1 + std::abs(dE))) << material;
      }
    }
  }
}
