#include "solver/electro/fem.h"

#include <Eigen/Dense>
#include <sstream>
#include <string>

#include "solver/core/errors.h"

namespace systole::electro {
namespace {

// Gradients (cm^-1, rows) of the barycentric basis functions of cell c and its measure.
struct CellGeometry {
  Eigen::Matrix<double, 4, 3> grad;
  double measure;
};

CellGeometry cell_geometry(const ElectroMesh& m, std::size_t c) {
  const auto& n = m.cell[c];
  const Vec3 x0 = m.position_mm[n[0]] * kCmPerMm;
  CellGeometry g;
  g.grad.setZero();
  if (m.cell_dim == 2) {
    Eigen::Matrix<double, 3, 2> J;
    J.col(0) = m.position_mm[n[1]] * kCmPerMm - x0;
    J.col(1) = m.position_mm[n[2]] * kCmPerMm - x0;
    const Eigen::Matrix2d G = J.transpose() * J;
    const double det = G.determinant();
    g.measure = 0.5 * std::sqrt(std::max(det, 0.0));
    if (!(g.measure > 1e-14 * G.trace())) {
      throw InputError("electro mesh: triangle " + std::to_string(c) + " is degenerate");
    }
    // grad(lambda_k) for k = 1, 2: columns of J G^{-1}.
    const Eigen::Matrix<double, 3, 2> D = J * G.inverse();
    g.grad.row(1) = D.col(0).transpose();
    g.grad.row(2) = D.col(1).transpose();
    g.grad.row(0) = -(g.grad.row(1) + g.grad.row(2));
  } else {
    Eigen::Matrix3d J;
    for (int k = 0; k < 3; ++k) J.col(k) = m.position_mm[n[k + 1]] * kCmPerMm - x0;
    const double det = J.determinant();
    g.measure = std::abs(det) / 6.0;
    if (!(g.measure > 0)) throw InputError("electro mesh: tetrahedron " + std::to_string(c) + " is degenerate");
    const Eigen::Matrix3d Jit = J.inverse().transpose();  // columns: grad(lambda_1..3)
    for (int k = 0; k < 3; ++k) g.grad.row(k + 1) = Jit.col(k).transpose();
    g.grad.row(0) = -(g.grad.row(1) + g.grad.row(2) + g.grad.row(3));
  }
  return g;
}

SparseMatrix from_triplets(std::size_t n, const std::vector<Eigen::Triplet<double>>& t) {
  SparseMatrix A(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  A.setFromTriplets(t.begin(), t.end());
  A.makeCompressed();
  return A;
}

}  // namespace

std::vector<double> cell_measures_cm(const ElectroMesh& mesh) {
  std::vector<double> out(mesh.cell_count());
  for (std::size_t c = 0; c < mesh.cell_count(); ++c) out[c] = cell_geometry(mesh, c).measure;
  return out;
}

SparseMatrix assemble_mass(const ElectroMesh& mesh) {
  const int k = mesh.nodes_per_cell();
  const double denom = (mesh.cell_dim + 1.0) * (mesh.cell_dim + 2.0);
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(mesh.cell_count() * k * k);
  for (std::size_t c = 0; c < mesh.cell_count(); ++c) {
    const double w = cell_geometry(mesh, c).measure / denom;
    for (int a = 0; a < k; ++a)
      for (int b = 0; b < k; ++b) t.emplace_back(mesh.cell[c][a], mesh.cell[c][b], w * (a == b ? 2.0 : 1.0));
  }
  return from_triplets(mesh.node_count(), t);
}

Eigen::VectorXd lumped_mass(const ElectroMesh& mesh) {
  const SparseMatrix M = assemble_mass(mesh);
  return M * Eigen::VectorXd::Ones(M.cols());
}

SparseMatrix assemble_stiffness(const ElectroMesh& mesh, const Conductivity& sigma,
                                const std::vector<double>& cell_scale) {
  if (!(sigma.fibre_ms_per_cm > 0) || !(sigma.cross_ms_per_cm > 0)) {
    std::ostringstream os;
    os << "conductivity (fibre " << sigma.fibre_ms_per_cm << ", cross " << sigma.cross_ms_per_cm
       << ") mS/cm: both must be > 0";
    throw InputError(os.str());
  }
  if (!cell_scale.empty() && cell_scale.size() != mesh.cell_count())
    throw InputError("conductivity cell_scale: " + std::to_string(cell_scale.size()) + " factors for " +
                     std::to_string(mesh.cell_count()) + " cells");
  const int k = mesh.nodes_per_cell();
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(mesh.cell_count() * k * k);
  for (std::size_t c = 0; c < mesh.cell_count(); ++c) {
    const CellGeometry g = cell_geometry(mesh, c);
    const Vec3& f = mesh.fibre[c];
    const Eigen::Matrix3d S = sigma.cross_ms_per_cm * Eigen::Matrix3d::Identity() +
                              (sigma.fibre_ms_per_cm - sigma.cross_ms_per_cm) * f * f.transpose();
    const double scale = cell_scale.empty() ? 1.0 : cell_scale[c];
    const Eigen::Matrix<double, 4, 4> Ke = (scale * g.measure) * g.grad * S * g.grad.transpose();
    for (int a = 0; a < k; ++a)
      for (int b = 0; b < k; ++b) t.emplace_back(mesh.cell[c][a], mesh.cell[c][b], Ke(a, b));
  }
  return from_triplets(mesh.node_count(), t);
}

}  // namespace systole::electro
