// The left heart's EP set-up shared by the scenes that run EP on a heart (electro,
// electromechanics, fsi/fsei's fsei): domains, cell models, the seed's stimuli, the Purkinje
// surrogate, the probes (left_heart_ep.h).
#include "solver/scene/left_heart_ep.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "solver/core/errors.h"
#include "solver/geometry/left_heart.h"

namespace systole::scene {
namespace {

using electro::ElectroMesh;
using electro::StimulusRegion;
using electro::StimulusSpec;
using electro::Vec3;

std::size_t first_tagged(const ElectroMesh& m, std::uint32_t bits, int domain) {
  for (std::size_t i = 0; i < m.node_count(); ++i)
    if ((m.node_region[i] & bits) && m.node_domain[i] == domain) return i;
  return m.node_count();
}

// Purkinje surrogate (ours; docs/electro.md): the left heart has no Purkinje network, so a
// single His site excites the LV wall at myocardial speed (LV total activation ~194 ms vs
// 60-80 ms, Durrer et al. 1970). Instead, `purkinje_sites` early-activation sites are spread
// over the LV by farthest-point sampling (geodesic spread approximated by straight-line
// distance) starting from the His site; site k is a sphere of kPurkinjeSiteRadiusMm (LV nodes
// only) stimulated at av_delay + |x_k - x_His| / purkinje_conduction_velocity (1 m/s = 1 mm/ms),
// i.e. the terminals of a network conducting at that velocity along straight branches.
constexpr double kPurkinjeSiteRadiusMm = 3.0;  // ours: >= 1.5 edges of the 2 mm default mesh

template <class Stim>
void add_purkinje_sites(const ElectroMesh& m, std::size_t his_node, int lv_domain, const config::Electro& e,
                        Stim&& stim, double av_delay_ms) {
  std::vector<double> dist(m.node_count(), std::numeric_limits<double>::infinity());
  auto update = [&](std::size_t from) {
    for (std::size_t i = 0; i < m.node_count(); ++i)
      if (m.node_domain[i] == lv_domain) dist[i] = std::min(dist[i], (m.position_mm[i] - m.position_mm[from]).norm());
  };
  update(his_node);
  const Vec3 his = m.position_mm[his_node];
  for (int k = 0; k < e.purkinje_sites; ++k) {
    std::size_t far = m.node_count();
    double d = 0;
    for (std::size_t i = 0; i < m.node_count(); ++i)
      if (m.node_domain[i] == lv_domain && dist[i] > d) {
        d = dist[i];
        far = i;
      }
    if (far == m.node_count() || d <= kPurkinjeSiteRadiusMm) break;  // the LV is covered
    update(far);
    StimulusRegion r;
    r.kind = StimulusRegion::Kind::kSphere;
    r.centre_mm = m.position_mm[far];
    r.radius_mm = kPurkinjeSiteRadiusMm;
    r.domain = lv_domain;
    stim("purkinje_site_" + std::to_string(k), r,
         av_delay_ms + (m.position_mm[far] - his).norm() / e.purkinje_conduction_velocity_m_per_s);
  }
}

}  // namespace

// The tissue options every EP scene takes from the scenario (conductivities, chi, C_m, time
// step, splitting, threshold, k_tau), with the given cell models and stimuli.
electro::TissueOptions ep_tissue_options(const config::Scenario& scenario, std::vector<std::string> models,
                                         std::vector<StimulusSpec> stimuli) {
  const config::Electro& e = scenario.electro;
  electro::TissueOptions o;
  o.formulation = electro::formulation_from_name(e.model);
  o.splitting = electro::splitting_from_name(e.splitting);
  o.dt_ms = e.time_step_ms;
  o.chi_per_cm = e.surface_to_volume_per_cm;
  o.cm_uf_per_cm2 = e.membrane_capacitance_uf_per_cm2;
  o.sigma_i = {e.sigma_i_fibre_ms_per_cm, e.sigma_i_cross_ms_per_cm};
  o.sigma_e = {e.sigma_e_fibre_ms_per_cm, e.sigma_e_cross_ms_per_cm};
  o.domain_cell_models = std::move(models);
  o.stimuli = std::move(stimuli);
  o.activation_threshold_mv = e.activation_threshold_mv;
  o.tension_k_kpa = scenario.tissue.active_tension_k_kpa;
  o.tension_time_scale_ms = scenario.tissue.active_tension_time_scale_ms;
  o.threads = e.threads;
  return o;
}

LeftHeartEp left_heart_ep(const config::Scenario& scenario, const geometry::TriMesh& lv,
                          const geometry::TriMesh& la) {
  return heart_ep(scenario, &lv, &la);
}

LeftHeartEp heart_ep(const config::Scenario& scenario, const geometry::TriMesh* lv_body,
                     const geometry::TriMesh* la_body) {
  if (!lv_body && !la_body) throw InputError("electro: a heart needs an LV and/or an LA body");
  const config::Electro& e = scenario.electro;
  const double period_ms = scenario.period_ms();
  std::vector<StimulusSpec> stimuli;
  auto stim = [&](std::string name, StimulusRegion region, double start_ms) {
    stimuli.push_back({std::move(name), std::move(region), e.stimulus.amplitude_ua_per_cm2, e.stimulus.duration_ms,
                       start_ms, period_ms});
  };
  LeftHeartEp ep;
  std::vector<const geometry::TriMesh*> bodies;
  std::vector<std::string> models;
  std::vector<double> scale;
  ep.lv_domain = ep.la_domain = -1;
  if (lv_body) {
    ep.lv_domain = static_cast<int>(bodies.size());
    bodies.push_back(lv_body);
    models.push_back(e.lv_cell_model);
    scale.push_back(1.0);
  }
  if (la_body) {
    ep.la_domain = static_cast<int>(bodies.size());
    bodies.push_back(la_body);
    models.push_back(e.la_cell_model);
    scale.push_back(e.la_conductivity_scale);  // ours
  }
  ep.mesh = electro::from_surfaces(bodies);
  const ElectroMesh& mesh = ep.mesh;
  const std::size_t n = mesh.node_count();
  std::size_t his_node = n, apex_node = n, bb_node = n;
  if (ep.la_domain >= 0) {
    StimulusRegion bb;
    bb.kind = StimulusRegion::Kind::kTagged;
    bb.region_bits = geometry::kBachmannBundle;
    bb.domain = ep.la_domain;
    stim("bachmann_bundle", bb, 0.0);
    bb_node = first_tagged(mesh, geometry::kBachmannBundle, ep.la_domain);
  }
  if (ep.lv_domain >= 0) {
    StimulusRegion his;
    his.kind = StimulusRegion::Kind::kTagged;
    his.region_bits = geometry::kHisBundle;
    his.domain = ep.lv_domain;
    stim("his_bundle", his, scenario.av_delay_ms);
    his_node = first_tagged(mesh, geometry::kHisBundle, ep.lv_domain);
    if (e.purkinje && his_node < n) add_purkinje_sites(mesh, his_node, ep.lv_domain, e, stim, scenario.av_delay_ms);
    apex_node = first_tagged(mesh, geometry::kLvApex, ep.lv_domain);
  }
  if (his_node < n) ep.probes.push_back({"his_bundle", his_node});
  if (apex_node < n) ep.probes.push_back({"lv_apex", apex_node});
  if (bb_node < n) ep.probes.push_back({"bachmann_bundle", bb_node});
  ep.options = ep_tissue_options(scenario, std::move(models), std::move(stimuli));
  ep.options.domain_conductivity_scale = std::move(scale);
  return ep;
}

}  // namespace systole::scene
