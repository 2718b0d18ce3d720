// P1 FEM on triangles in 3-D and tetrahedra: mass sums to the area / volume, stiffness kills
// constants, is exact for linear fields (energy and interior residual), conductivity frame.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "solver/core/errors.h"
#include "solver/electro/fem.h"
#include "solver/electro/mesh.h"

namespace systole::electro {
namespace {

Eigen::VectorXd nodal(const ElectroMesh& m, const Vec3& g) {
  Eigen::VectorXd u(static_cast<Eigen::Index>(m.node_count()));
  for (std::size_t i = 0; i < m.node_count(); ++i) u[static_cast<Eigen::Index>(i)] = g.dot(m.position_mm[i] * kCmPerMm) + 0.3;
  return u;
}

// A sheet rotated into a tilted plane: tests the 3-D embedding of the triangle path.
ElectroMesh tilted_sheet(const Eigen::Matrix3d& R) {
  ElectroMesh m = make_sheet(10.0, 6.0, 1.0, 30.0);
  for (auto& x : m.position_mm) x = R * x;
  for (auto& f : m.fibre) f = R * f;
  return m;
}

Eigen::Matrix3d rotation() {
  return (Eigen::AngleAxisd(0.4, Vec3(1, 2, 3).normalized())).toRotationMatrix();
}

TEST(Fem, MassSumsToAreaAndVolume) {
  const ElectroMesh s = tilted_sheet(rotation());
  EXPECT_NEAR(lumped_mass(s).sum(), 1.0 * 0.6, 1e-12);  // cm^2
  const ElectroMesh b = make_slab(4.0, 3.0, 2.0, 0.5, 0.0);
  EXPECT_NEAR(lumped_mass(b).sum(), 0.4 * 0.3 * 0.2, 1e-14);  // cm^3
}

TEST(Fem, StiffnessKillsConstants) {
  for (const ElectroMesh& m : {tilted_sheet(rotation()), make_slab(4.0, 3.0, 2.0, 0.5, 20.0)}) {
    const SparseMatrix K = assemble_stiffness(m, {3.0, 0.5});
    const Eigen::VectorXd r = K * Eigen::VectorXd::Ones(K.cols());
    EXPECT_LT(r.cwiseAbs().maxCoeff(), 1e-12 * K.diagonal().maxCoeff());
  }
}

TEST(Fem, ExactForLinearFieldsOnTriangles) {
  const Eigen::Matrix3d R = rotation();
  const ElectroMesh m = tilted_sheet(R);
  const double sf = 3.0, sc = 0.5;
  const SparseMatrix K = assemble_stiffness(m, {sf, sc});
  // In-plane gradient (cm^-1) expressed in the fibre frame: energy = area * g^T S g.
  const Vec3 f = m.fibre[0];
  const Vec3 g = R * Vec3(1.5, -0.7, 0.0);
  const Eigen::VectorXd u = nodal(m, g);
  const double gf = g.dot(f);
  const double exact = 0.6 * (sc * g.squaredNorm() + (sf - sc) * gf * gf);
  EXPECT_NEAR(u.dot(K * u), exact, 1e-12 * exact);
  // Interior rows of K u vanish (div(S grad u) = 0 for linear u and constant S).
  const Eigen::VectorXd r = K * u;
  for (std::size_t i = 0; i < m.node_count(); ++i) {
    const Vec3 p = R.transpose() * m.position_mm[i];
    if (p.x() > 0.5 && p.x() < 9.5 && p.y() > 0.5 && p.y() < 5.5) {
      EXPECT_NEAR(r[static_cast<Eigen::Index>(i)], 0.0, 1e-12);
    }
  }
}

TEST(Fem, ExactForLinearFieldsOnTetrahedra) {
  const ElectroMesh m = make_slab(4.0, 3.0, 2.0, 0.5, 35.0);
  const double sf = 2.0, sc = 0.25;
  const SparseMatrix K = assemble_stiffness(m, {sf, sc});
  const Vec3 g(0.4, 1.1, -0.8);
  const Eigen::VectorXd u = nodal(m, g);
  const Vec3 f = m.fibre[0];
  const double exact = 0.024 * (sc * g.squaredNorm() + (sf - sc) * g.dot(f) * g.dot(f));
  EXPECT_NEAR(u.dot(K * u), exact, 1e-12 * exact);
  const Eigen::VectorXd r = K * u;
  for (std::size_t i = 0; i < m.node_count(); ++i) {
    const Vec3& p = m.position_mm[i];
    const bool interior = p.x() > 0.25 && p.x() < 3.75 && p.y() > 0.25 && p.y() < 2.75 && p.z() > 0.25 && p.z() < 1.75;
    if (interior) {
      EXPECT_NEAR(r[static_cast<Eigen::Index>(i)], 0.0, 1e-11);
    }
  }
}

TEST(Fem, MassIsExactForLinearFields) {
  // 1^T M u = integral of u: exact for P1 (here u linear, integral = volume * u(centroid)).
  const ElectroMesh m = make_slab(4.0, 3.0, 2.0, 0.5, 0.0);
  const Vec3 g(0.4, 1.1, -0.8);
  const Eigen::VectorXd u = nodal(m, g);
  const double exact = 0.024 * (g.dot(Vec3(0.2, 0.15, 0.1)) + 0.3);
  EXPECT_NEAR(lumped_mass(m).dot(u), exact, 1e-14);
}

TEST(Fem, NonPositiveConductivityIsAnInputError) {
  const ElectroMesh m = make_sheet(2.0, 2.0, 1.0, 0.0);
  EXPECT_THROW((void)assemble_stiffness(m, {0.0, 1.0}), InputError);
  EXPECT_THROW((void)assemble_stiffness(m, {1.0, -1.0}), InputError);
}

// Per-cell conductivity factor (the scene's per-domain scale, ours): a cell's element matrix is
// multiplied by its factor; a factor list of the wrong length is an InputError.
TEST(Fem, CellScaleMultipliesTheElementMatrices) {
  const ElectroMesh m = make_sheet(4.0, 3.0, 1.0, 20.0);
  const SparseMatrix K = assemble_stiffness(m, {3.0, 0.5});
  const SparseMatrix K3 = assemble_stiffness(m, {3.0, 0.5}, std::vector<double>(m.cell_count(), 3.0));
  EXPECT_LT((SparseMatrix(K3 - 3.0 * K)).norm(), 1e-12 * K.norm());
  std::vector<double> half(m.cell_count(), 1.0);
  for (std::size_t c = 0; c < half.size() / 2; ++c) half[c] = 2.0;
  const SparseMatrix Kh = assemble_stiffness(m, {3.0, 0.5}, half);
  EXPECT_GT((SparseMatrix(Kh - K)).norm(), 1e-3 * K.norm());
  EXPECT_LT((Kh * Eigen::VectorXd::Ones(Kh.cols())).norm(), 1e-12 * Kh.norm());  // constants still in the null space
  EXPECT_THROW((void)assemble_stiffness(m, {3.0, 0.5}, std::vector<double>(3, 1.0)), InputError);
}

TEST(Fem, GeneratedMeshesAreConsistent) {
  const ElectroMesh s = make_sheet(10.0, 6.0, 1.0, 0.0);
  EXPECT_EQ(s.node_count(), 11u * 7u);
  EXPECT_EQ(s.cell_count(), 2u * 10u * 6u);
  s.check();
  const ElectroMesh b = make_slab(4.0, 3.0, 2.0, 0.5, 0.0);
  EXPECT_EQ(b.node_count(), 9u * 7u * 5u);
  EXPECT_EQ(b.cell_count(), 6u * 8u * 6u * 4u);
  b.check();
  EXPECT_THROW((void)make_sheet(1.0, 1.0, 0.0, 0.0), InputError);
}

}  // namespace
}  // namespace systole::electro
