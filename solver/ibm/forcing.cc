#include "solver/ibm/forcing.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <string>

#include "solver/core/errors.h"

namespace systole::ibm {

void validate(const ForcingParameters& p) {
  if (p.iterations < 1 || p.iterations > 20) {
    std::ostringstream m;
    m << "ibm.forcing_iterations = " << p.iterations << " is out of range [1, 20]";
    throw InputError(m.str());
  }
  if (!(p.carry_over_factor > 0 && p.carry_over_factor <= 1)) {
    std::ostringstream m;
    m << "ibm carry-over factor = " << p.carry_over_factor << " is out of range (0, 1]";
    throw InputError(m.str());
  }
  if (!(p.carry_over_increment_share > 0 && p.carry_over_increment_share <= 1)) {
    std::ostringstream m;
    m << "ibm carry-over increment share = " << p.carry_over_increment_share << " is out of range (0, 1]";
    throw InputError(m.str());
  }
  if (!(p.carry_over_exclusion_cells >= 0 && p.carry_over_exclusion_cells <= 4)) {
    std::ostringstream m;
    m << "ibm carry-over exclusion = " << p.carry_over_exclusion_cells << " cells is out of range [0, 4]";
    throw InputError(m.str());
  }
  if (!(p.carry_over_exclusion_rigid_cells >= 0 && p.carry_over_exclusion_rigid_cells <= 4)) {
    std::ostringstream m;
    m << "ibm carry-over exclusion next to a rigid body = " << p.carry_over_exclusion_rigid_cells
      << " cells is out of range [0, 4]";
    throw InputError(m.str());
  }
  if (!(p.carry_over_exclusion_rigid_wall_cells >= 0 && p.carry_over_exclusion_rigid_wall_cells <= 4)) {
    std::ostringstream m;
    m << "ibm carry-over exclusion between a rigid body and a wall = " << p.carry_over_exclusion_rigid_wall_cells
      << " cells is out of range [0, 4]";
    throw InputError(m.str());
  }
  if (!(p.rebuild_tolerance_cells >= 0 && p.rebuild_tolerance_cells <= 0.5)) {
    std::ostringstream m;
    m << "ibm rebuild tolerance = " << p.rebuild_tolerance_cells << " cells is out of range [0, 0.5]";
    throw InputError(m.str());
  }
}

DirectForcing::DirectForcing(const grid::Slabs& slabs, const Markers& markers, ForcingParameters parameters)
    : slabs_(slabs), markers_(markers), par_((validate(parameters), parameters)), transfer_(slabs, markers, parameters.kernel) {
  transfer_.set_rebuild_tolerance(par_.rebuild_tolerance_cells * markers.h());
  if (par_.iterations > 1 || par_.carry_over) {
    work_u_ = std::make_unique<grid::XFaceField>(slabs);
    work_v_ = std::make_unique<grid::YFaceField>(slabs);
    work_w_ = std::make_unique<grid::ZFaceField>(slabs);
  }
  update_carry_mask();
}

DirectForcing::ExclusionRadii DirectForcing::carry_over_exclusion_radii() const {
  ExclusionRadii r;
  r.pair_cells = par_.carry_over_exclusion_cells;
  r.rigid_cells = std::max(par_.carry_over_exclusion_rigid_cells, r.pair_cells);
  r.rigid_wall_cells = std::max(par_.carry_over_exclusion_rigid_wall_cells, r.rigid_cells);
  return r;
}

bool DirectForcing::carries_over(std::size_t marker) const {
  if (marker >= markers_.size())
    throw std::out_of_range("DirectForcing::carries_over: marker " + std::to_string(marker) + " of " +
                            std::to_string(markers_.size()));
  return carries_.empty() || carries_[marker] != 0;
}

// A counting sort of the markers into cells of size r h over the box (grid units; markers lie
// inside it, Markers checks that); a marker is excluded when a marker of another body lies
// within r h (the 27 neighbouring cells checked). O(markers + cells); the box is not wrapped
// periodically (bodies stay clear of the x, y faces). Same result on every rank (all ranks hold
// all markers). For cost (ours): per occupied cell, the bodies present in its 27 neighbours as a
// bit set (up to 64 bodies; beyond, every marker takes the distance test): a marker whose
// neighbourhood holds only its own body needs no distance test; the buffers are kept between
// calls (no page faults per coupling pass).
void DirectForcing::update_carry_mask() {
  carries_.clear();
  excluded_ = 0;
  // The exclusion radius of a pair by the bodies' kinds: 0 a two-sided deformable body (a
  // leaflet), 1 a one-sided deformable body (a wall), 2 a rigid body; kind per body computed
  // once here, not in the pair loop.
  const ExclusionRadii radii = carry_over_exclusion_radii();
  const double r_pair = radii.pair_cells * markers_.h(), r_rigid = radii.rigid_cells * markers_.h(),
               r_wall = radii.rigid_wall_cells * markers_.h();
  if (!par_.carry_over || r_wall <= 0) return;
  const MarkerArrays& m = markers_.markers();
  const std::size_t n = m.size();
  const grid::Grid& g = slabs_.grid();
  std::vector<int> kind_of_body(markers_.bodies().size());
  for (std::size_t k = 0; k < kind_of_body.size(); ++k) {
    const BodyOptions& o = markers_.bodies()[k].options;
    kind_of_body[k] = o.rigid ? 2 : (o.sides == Sides::one ? 1 : 0);
  }
  const double r = r_wall;  // hash cells of the widest radius
  std::array<std::array<double, 3>, 3> r2{};
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < 3; ++c) {
      const double rr = (a == 2 && c == 1) || (a == 1 && c == 2) ? r_wall : (a == 2 || c == 2 ? r_rigid : r_pair);
      r2[a][c] = rr * rr;
    }
  auto kind = [&](std::size_t marker) { return kind_of_body[static_cast<std::size_t>(m.body[marker])]; };
  auto rigid = [&](std::size_t marker) { return kind(marker) == 2; };
  const std::array<int, 3> dims{static_cast<int>(g.lx() / r) + 1, static_cast<int>(g.ly() / r) + 1,
                                static_cast<int>(g.lz() / r) + 1};
  auto coord = [&](double x, int d) { return std::clamp(static_cast<int>(std::floor(x / r)), 0, dims[d] - 1); };
  auto index = [&](int i, int j, int k) {
    return static_cast<std::size_t>(i) + static_cast<std::size_t>(dims[0]) * (j + static_cast<std::size_t>(dims[1]) * k);
  };
  const std::size_t cells = index(0, 0, dims[2]);
  std::vector<std::uint32_t>&start = mask_start_, &order = mask_order_, &cell_of = mask_cell_of_;
  std::vector<std::uint64_t>& present = mask_bodies_;  // per cell: bit (body % 64) of its markers
  start.assign(cells + 1, 0);
  present.assign(cells, 0);
  cell_of.resize(n);
  order.resize(n);
  const bool bit_per_body = markers_.bodies().size() <= 64;
  auto bit = [](std::int32_t body) { return std::uint64_t{1} << (static_cast<unsigned>(body) % 64u); };
  for (std::size_t b = 0; b < n; ++b) {
    const Vec3& x = m.position[b];
    cell_of[b] = static_cast<std::uint32_t>(index(coord(x.x(), 0), coord(x.y(), 1), coord(x.z(), 2)));
    ++start[cell_of[b] + 1];
    present[cell_of[b]] |= bit(m.body[b]);
  }
  for (std::size_t c = 0; c < cells; ++c) start[c + 1] += start[c];
  {
    std::vector<std::uint32_t>& fill = mask_fill_;
    fill.assign(start.begin(), start.end() - 1);
    for (std::size_t b = 0; b < n; ++b) order[fill[cell_of[b]]++] = static_cast<std::uint32_t>(b);
  }
  carries_.assign(n, 1);
  for (int ck = 0; ck < dims[2]; ++ck)
    for (int cj = 0; cj < dims[1]; ++cj)
      for (int ci = 0; ci < dims[0]; ++ci) {
        const std::size_t cell = index(ci, cj, ck);
        if (start[cell] == start[cell + 1]) continue;
        std::uint64_t around = 0;
        for (int k = std::max(ck - 1, 0); k <= std::min(ck + 1, dims[2] - 1); ++k)
          for (int j = std::max(cj - 1, 0); j <= std::min(cj + 1, dims[1] - 1); ++j)
            for (int i = std::max(ci - 1, 0); i <= std::min(ci + 1, dims[0] - 1); ++i) around |= present[index(i, j, k)];
        for (std::uint32_t q0 = start[cell]; q0 < start[cell + 1]; ++q0) {
          const std::size_t b = order[q0];
          if (bit_per_body && (around & ~bit(m.body[b])) == 0) continue;  // only its own body around
          if (!par_.carry_over_exclusion_rigid && rigid(b)) continue;
          const Vec3& x = m.position[b];
          const std::array<double, 3>& r2_b = r2[kind(b)];
          bool near_other = false;
          for (int k = std::max(ck - 1, 0); k <= std::min(ck + 1, dims[2] - 1) && !near_other; ++k)
            for (int j = std::max(cj - 1, 0); j <= std::min(cj + 1, dims[1] - 1) && !near_other; ++j)
              for (int i = std::max(ci - 1, 0); i <= std::min(ci + 1, dims[0] - 1) && !near_other; ++i) {
                const std::size_t c = index(i, j, k);
                for (std::uint32_t q = start[c]; q < start[c + 1]; ++q) {
                  const std::size_t o = order[q];
                  if (m.body[o] != m.body[b] && (m.position[o] - x).squaredNorm() < r2_b[kind(o)]) {
                    near_other = true;
                    break;
                  }
                }
              }
          if (near_other) {
            carries_[b] = 0;
            ++excluded_;
          }
        }
      }
}

SlipStats DirectForcing::slip_of(const std::vector<Vec3>& interpolated) const {
  const MarkerArrays& m = markers_.markers();
  SlipStats s;
  double sum2 = 0;
  for (std::size_t b = 0; b < m.size(); ++b) {
    if (!markers_.active(b)) continue;
    const double e = (m.velocity[b] - interpolated[b]).norm();
    sum2 += e * e;
    s.max = std::max(s.max, e);
    ++s.markers;
  }
  s.rms = s.markers ? std::sqrt(sum2 / static_cast<double>(s.markers)) : 0.0;
  return s;
}

void DirectForcing::set_carried_force(std::vector<Vec3> force) {
  if (!force.empty() && force.size() != markers_.markers().size())
    throw std::invalid_argument("DirectForcing::set_carried_force: " + std::to_string(force.size()) +
                                " values for " + std::to_string(markers_.markers().size()) + " markers");
  previous_ = std::move(force);
}

void DirectForcing::export_state(StateArchive& archive, const std::string& prefix) const {
  if (!previous_.empty()) archive.put_vectors(prefix + "carried_force", previous_);
}

void DirectForcing::import_state(const StateArchive& archive, const std::string& prefix) {
  if (archive.has(prefix + "carried_force"))
    set_carried_force(archive.get_vectors<Vec3>(prefix + "carried_force", static_cast<long>(markers_.markers().size())));
}

SlipStats DirectForcing::slip(const ConstVelocityView& u) const { return slip_of(transfer_.interpolate(u)); }

const ForcingReport& DirectForcing::apply(double dt, const ConstVelocityView& u_hat, VelocityView f,
                                          const Vec3& uniform_force, double increment_share_factor) {
  if (!(increment_share_factor > 0 && increment_share_factor <= 1)) {
    std::ostringstream m;
    m << "ibm forcing: increment_share_factor = " << increment_share_factor << " is out of range (0, 1]";
    throw InputError(m.str());
  }
  const MarkerArrays& m = markers_.markers();
  const std::size_t n = m.size();
  force_.assign(n, Vec3::Zero());
  increment_.assign(n, Vec3::Zero());
  report_ = ForcingReport{};
  // u* = û + Δt f on the interior, halos exchanged (the multi-direct passes, the carry-over).
  auto update = [&](const auto& uh, const auto& ff, auto& work) {
    for (int k = 0; k < work.k_count(); ++k)
      for (int j = 0; j < work.ny(); ++j)
        for (int i = 0; i < work.nx(); ++i) work(i, j, k) = uh(i, j, k) + dt * ff(i, j, k);
    grid::exchange_halos(work, slabs_);
  };
  // Pass 1 (eq 3): F = (V_b − û(X_b))/Δt, spread (eq 6).
  std::vector<Vec3>& U = interpolated_;
  transfer_.interpolate(u_hat, U);
  for (Vec3& x : U) x += dt * uniform_force;
  report_.slip_before = slip_of(U);
  if (par_.carry_over && previous_.size() == n) {
    // Start from the previous step's force (active markers only), then correct what it leaves.
    for (std::size_t b = 0; b < n; ++b)
      force_[b] = markers_.active(b) && (carries_.empty() || carries_[b]) ? Vec3(par_.carry_over_factor * previous_[b])
                                                                         : Vec3::Zero();
    transfer_.spread(force_, f);
    update(u_hat.u, f.u, *work_u_);
    update(u_hat.v, f.v, *work_v_);
    update(u_hat.w, f.w, *work_w_);
    transfer_.interpolate(ConstVelocityView{*work_u_, *work_v_, *work_w_}, U);
    for (Vec3& x : U) x += dt * uniform_force;
  }
  const double w = par_.carry_over_increment_share * increment_share_factor;
  const bool share_increments = par_.carry_over && w < 1;
  if (share_increments) start_ = force_;  // F_start (zero where nothing was carried)
  for (int pass = 0; pass < par_.iterations; ++pass) {
    for (std::size_t b = 0; b < n; ++b)
      increment_[b] = markers_.active(b) ? Vec3((m.velocity[b] - U[b]) / dt) : Vec3::Zero();
    for (std::size_t b = 0; b < n; ++b) force_[b] += increment_[b];
    transfer_.spread(increment_, f);
    ++report_.iterations;
    // The last pass (the seed's single one among them) is not re-interpolated: only a slip
    // after it would read u* = û + Δt f again, and no caller needs one (ours, for cost: one of
    // the 5 interpolations of a step with 3 passes and the carry-over; the results are the same).
    if (pass + 1 == par_.iterations) break;
    // then interpolate u* = û + Δt f again (multi-direct).
    update(u_hat.u, f.u, *work_u_);
    update(u_hat.v, f.v, *work_v_);
    update(u_hat.w, f.w, *work_w_);
    transfer_.interpolate(ConstVelocityView{*work_u_, *work_v_, *work_w_}, U);
    for (Vec3& x : U) x += dt * uniform_force;
  }
  Vec3 total = Vec3::Zero();
  for (std::size_t b = 0; b < n; ++b) total += force_[b] * markers_.forcing_volume(b);
  report_.total_force = total;
  if (share_increments) {
    // The carried force keeps only the share w of this step's corrections.
    previous_.resize(n);
    for (std::size_t b = 0; b < n; ++b) previous_[b] = start_[b] + w * (force_[b] - start_[b]);
  } else if (par_.carry_over) {
    previous_ = force_;
  }
  return report_;
}

}  // namespace systole::ibm
