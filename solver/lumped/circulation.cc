#include "solver/lumped/circulation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "solver/core/errors.h"

namespace systole::lumped {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Initial pressure in the systemic compliance (ours): near the diastolic aortic pressure of
// the periodic state, so the loop settles in few beats. The seed pre-loads its aorta to 60.
constexpr double kInitialSystemicPressure_mmhg = 80.0;

const char* state_name(int i) {
  static const char* names[] = {"lv_volume_ml",
                                "la_volume_ml",
                                "systemic_compliance_volume_ml",
                                "pulmonary_venous_compliance_volume_ml",
                                "mitral_flow_ml_s",
                                "aortic_flow_ml_s"};
  return names[i];
}

// Root of a strictly decreasing scalar function f (returns {value, derivative}): Newton's
// method kept inside a bracket that it grows and shrinks, bisection when Newton leaves it.
// Returns NaN if f is not finite (the caller's instability check reports it).
template <class F>
double solve_decreasing(F&& f, double x0) {
  double lo = -kInf, hi = kInf;  // f(lo) > 0 > f(hi)
  double x = x0;
  for (int it = 0; it < 200; ++it) {
    const auto [fx, dfx] = f(x);
    if (!std::isfinite(fx) || !std::isfinite(dfx)) return std::numeric_limits<double>::quiet_NaN();
    if (fx == 0) return x;
    (fx > 0 ? lo : hi) = x;
    double next = dfx < 0 ? x - fx / dfx : kInf * (fx > 0 ? 1 : -1);
    if (!(next > lo && next < hi)) {
      if (std::isfinite(lo) && std::isfinite(hi)) {
        next = 0.5 * (lo + hi);
      } else {  // grow the bracket geometrically on its open side
        const double step = std::max(10.0, std::abs(x));
        next = std::isfinite(lo) ? lo + step : hi - step;
      }
    }
    if (std::abs(next - x) <= 1e-12 * std::max(1.0, std::abs(x))) return next;
    if (std::isfinite(lo) && std::isfinite(hi) && hi - lo <= 1e-12 * std::max(1.0, std::abs(x)))
      return 0.5 * (lo + hi);
    x = next;
  }
  return x;  // 200 safeguarded iterations on a monotone C^2 function: converged in practice
}

}  // namespace

Circulation::Circulation(const config::Scenario& s, const ExternalVolumes& external_in,
                         const PressureDriven& pressure_driven)
    : p_(s.lumped),
      lv_elastance_{s.lumped.lv.emin_mmhg_per_ml, s.lumped.lv.emax_mmhg_per_ml,
                    ChamberTiming::lv(s)},
      la_elastance_{s.lumped.la.emin_mmhg_per_ml, s.lumped.la.emax_mmhg_per_ml,
                    ChamberTiming::la(s)},
      // The aortic valve is in series with Zc; the smooth switch acts on the drop across both
      // (README "Valves"): open R_av + Zc, closed R_av / leak_fraction + Zc.
      mitral_(s.lumped.mitral_resistance_mmhg_s_per_ml,
              s.lumped.valve_backflow_conductance_fraction > 0
                  ? s.lumped.mitral_resistance_mmhg_s_per_ml /
                        s.lumped.valve_backflow_conductance_fraction
                  : kInf),
      aortic_(s.lumped.aortic_resistance_mmhg_s_per_ml +
                  s.lumped.aortic_characteristic_impedance_mmhg_s_per_ml,
              s.lumped.valve_backflow_conductance_fraction > 0
                  ? s.lumped.aortic_resistance_mmhg_s_per_ml /
                            s.lumped.valve_backflow_conductance_fraction +
                        s.lumped.aortic_characteristic_impedance_mmhg_s_per_ml
                  : kInf),
      mitral_inertial_(s.lumped.mitral_inertance_mmhg_s2_per_ml > 0),
      aortic_inertial_(s.lumped.aortic_inertance_mmhg_s2_per_ml > 0),
      lv_external_(external_in.lv_ml.has_value() && !pressure_driven.lv),
      la_external_(external_in.la_ml.has_value() && !pressure_driven.la),
      lv_pressure_driven_(pressure_driven.lv),
      la_pressure_driven_(pressure_driven.la) {
  if ((pressure_driven.lv && !external_in.lv_ml) || (pressure_driven.la && !external_in.la_ml))
    throw std::invalid_argument("Circulation: a pressure-driven chamber needs its initial volume in ExternalVolumes");
  const ExternalVolumes& external = external_in;
  if (lv_external_ && (mitral_inertial_ || aortic_inertial_))
    throw InputError(
        "an external LV needs lumped.mitral_inertance_mmhg_s2_per_ml = 0 and "
        "lumped.aortic_inertance_mmhg_s2_per_ml = 0 (an inertial valve flow does not depend "
        "on the chamber pressure, which then cannot be solved for)");
  if (la_external_ && mitral_inertial_)
    throw InputError("an external LA needs lumped.mitral_inertance_mmhg_s2_per_ml = 0");
  if ((lv_external_ || la_external_) && !(p_.valve_backflow_conductance_fraction > 0))
    throw InputError(
        "external chambers need lumped.valve_backflow_conductance_fraction > 0: with both "
        "valves closed the leak is what defines the chamber pressure");
  for (const auto& v : {external.lv_ml, external.la_ml})
    if (v && !(*v >= 0)) throw std::invalid_argument("external chamber volume must be >= 0");

  // Initial state (README "Initial state"): the systemic compliance at 80 mmHg, the LV, the LA
  // and the pulmonary veins at one common pressure p, all summing to the stressed volume.
  const double e_lv = lv_elastance_.at(0.0), e_la = la_elastance_.at(0.0);
  lv_elastance_now_ = e_lv;
  la_elastance_now_ = e_la;
  double budget = p_.stressed_blood_volume_ml;
  if (external.lv_ml) budget -= *external.lv_ml - p_.lv.v0_ml;
  if (external.la_ml) budget -= *external.la_ml - p_.la.v0_ml;
  const double c_s = p_.systemic_compliance_ml_per_mmhg;
  const double c_pv = p_.pulmonary_venous_compliance_ml_per_mmhg;
  const bool lv_given = external.lv_ml.has_value(), la_given = external.la_ml.has_value();
  const double capacity = (lv_given ? 0 : 1 / e_lv) + (la_given ? 0 : 1 / e_la) + c_pv;
  double p_sa = kInitialSystemicPressure_mmhg;
  double p = (budget - c_s * p_sa) / capacity;
  if (p < 0) p = p_sa = budget / (capacity + c_s);  // too little blood: all at one pressure
  y_[kLv] = lv_given ? *external.lv_ml : p_.lv.v0_ml + p / e_lv;
  y_[kLa] = la_given ? *external.la_ml : p_.la.v0_ml + p / e_la;
  imposed_ = {p, p};
  y_[kSystemic] = c_s * p_sa;
  y_[kPulmonary] = c_pv * p;
  y_[kMitralFlow] = 0;
  y_[kAorticFlow] = 0;
  lv_pressure_guess_ = la_pressure_guess_ = p;
  check(y_, 0.0, 0.0);
}

std::vector<double> Circulation::activation_breakpoints_s() const {
  std::vector<double> b = lv_elastance_.timing.breakpoints_s();
  for (double t : la_elastance_.timing.breakpoints_s()) b.push_back(t);
  std::sort(b.begin(), b.end());
  return b;
}

double Circulation::mitral_floor(double dp) const {
  return dp < 0 ? mitral_.closed_conductance() * dp : -kInf;
}

void Circulation::solve_external_pressures(double p_sa, double p_pv, const Rates& rates,
                                           double& p_lv, double& p_la) const {
  // LV balance: q_mitral(p_la - p_lv) - q_aortic(p_lv - p_sa) = dV_lv/dt, decreasing in p_lv.
  auto solve_lv = [&](double pla) {
    return solve_decreasing(
        [&](double plv) {
          const double f =
              mitral_.flow_ml_s(pla - plv) - aortic_.flow_ml_s(plv - p_sa) - rates.lv_ml_s;
          const double df =
              -(mitral_.conductance_slope(pla - plv) + aortic_.conductance_slope(plv - p_sa));
          return std::pair{f, df};
        },
        lv_pressure_guess_);
  };
  const double r_pv = p_.pulmonary_venous_resistance_mmhg_s_per_ml;
  if (la_external_) {
    // LA balance: q_pv(p_pv - p_la) - q_mitral(p_la - p_lv) = dV_la/dt, decreasing in p_la
    // (also when p_lv follows p_la through the LV balance, nested below).
    p_la = solve_decreasing(
        [&](double pla) {
          double plv = p_lv;
          double dplv_dpla = 0;
          if (lv_external_) {
            plv = solve_lv(pla);
            const double gm = mitral_.conductance_slope(pla - plv);
            const double ga = aortic_.conductance_slope(plv - p_sa);
            dplv_dpla = gm / (gm + ga);
          }
          const double gm = mitral_.conductance_slope(pla - plv);
          const double f = (p_pv - pla) / r_pv - mitral_.flow_ml_s(pla - plv) - rates.la_ml_s;
          const double df = -1.0 / r_pv - gm * (1.0 - dplv_dpla);
          return std::pair{f, df};
        },
        la_pressure_guess_);
    la_pressure_guess_ = p_la;
  }
  if (lv_external_) {
    p_lv = solve_lv(p_la);
    lv_pressure_guess_ = p_lv;
  }
}

Circulation::State Circulation::derivatives(const State& y, double e_lv, double e_la,
                                            const Rates& rates, Readout* out) const {
  const double p_sa = y[kSystemic] / p_.systemic_compliance_ml_per_mmhg;
  const double p_pv = y[kPulmonary] / p_.pulmonary_venous_compliance_ml_per_mmhg;
  double p_lv = lv_external_ ? 0 : lv_pressure_driven_ ? imposed_.lv_mmhg : e_lv * (y[kLv] - p_.lv.v0_ml);
  double p_la = la_external_ ? 0 : la_pressure_driven_ ? imposed_.la_mmhg : e_la * (y[kLa] - p_.la.v0_ml);
  if (lv_external_ || la_external_) solve_external_pressures(p_sa, p_pv, rates, p_lv, p_la);

  const double q_pv = (p_pv - p_la) / p_.pulmonary_venous_resistance_mmhg_s_per_ml;
  const double q_s = (p_sa - p_pv) / p_.systemic_resistance_mmhg_s_per_ml;
  State d{};
  // Mitral valve: smooth diode, or L dQ/dt = dp - R Q with the flow kept above the leak.
  const double dp_m = p_la - p_lv;
  double q_m;
  if (mitral_inertial_) {
    const double floor = mitral_floor(dp_m);
    q_m = std::max(y[kMitralFlow], floor);
    const double drive = dp_m - p_.mitral_resistance_mmhg_s_per_ml * q_m;
    d[kMitralFlow] =
        (y[kMitralFlow] > floor || drive > 0) ? drive / p_.mitral_inertance_mmhg_s2_per_ml : 0;
  } else {
    q_m = mitral_.flow_ml_s(dp_m);
  }
  // Aortic valve + Zc, same two laws on the drop from the LV to the compliance.
  const double dp_a = p_lv - p_sa;
  double q_a;
  if (aortic_inertial_) {
    const double floor = dp_a < 0 ? aortic_.closed_conductance() * dp_a : -kInf;
    q_a = std::max(y[kAorticFlow], floor);
    const double drive = dp_a - (p_.aortic_resistance_mmhg_s_per_ml +
                                 p_.aortic_characteristic_impedance_mmhg_s_per_ml) *
                                    q_a;
    d[kAorticFlow] =
        (y[kAorticFlow] > floor || drive > 0) ? drive / p_.aortic_inertance_mmhg_s2_per_ml : 0;
  } else {
    q_a = aortic_.flow_ml_s(dp_a);
  }
  d[kLv] = lv_external_ ? rates.lv_ml_s : q_m - q_a;
  d[kLa] = la_external_ ? rates.la_ml_s : q_pv - q_m;
  d[kSystemic] = q_a - q_s;
  d[kPulmonary] = q_s - q_pv;

  if (out) {
    out->lv_volume_ml = y[kLv];
    out->la_volume_ml = y[kLa];
    out->lv_pressure_mmhg = p_lv;
    out->la_pressure_mmhg = p_la;
    out->aortic_pressure_mmhg = p_sa + p_.aortic_characteristic_impedance_mmhg_s_per_ml * q_a;
    out->systemic_arterial_pressure_mmhg = p_sa;
    out->pulmonary_venous_pressure_mmhg = p_pv;
    out->mitral_flow_ml_s = q_m;
    out->aortic_flow_ml_s = q_a;
    out->systemic_flow_ml_s = q_s;
    out->pulmonary_venous_flow_ml_s = q_pv;
    out->total_volume_ml = y[kLv] + y[kLa] + y[kSystemic] + y[kPulmonary];
    out->lv_outflow_conductance_ml_s_per_mmhg =
        lv_external_ || lv_pressure_driven_ ? mitral_.conductance_slope(dp_m) + aortic_.conductance_slope(dp_a) : 0;
    out->la_outflow_conductance_ml_s_per_mmhg =
        la_external_ || la_pressure_driven_
            ? 1.0 / p_.pulmonary_venous_resistance_mmhg_s_per_ml + mitral_.conductance_slope(dp_m)
            : 0;
  }
  return d;
}

void Circulation::advance(double dt_s, const ExternalVolumes& at_end) {
  if (!(dt_s > 0)) throw std::invalid_argument("Circulation::advance: dt_s must be > 0");
  Rates rates;
  if (lv_external_) {
    if (!at_end.lv_ml || !(*at_end.lv_ml >= 0))
      throw std::invalid_argument("Circulation::advance: the external LV needs a volume >= 0");
    rates.lv_ml_s = (*at_end.lv_ml - y_[kLv]) / dt_s;
  }
  if (la_external_) {
    if (!at_end.la_ml || !(*at_end.la_ml >= 0))
      throw std::invalid_argument("Circulation::advance: the external LA needs a volume >= 0");
    rates.la_ml_s = (*at_end.la_ml - y_[kLa]) / dt_s;
  }
  // Classical RK4; the elastances are evaluated once per distinct stage time.
  const double t = time_s_, h = dt_s;
  const double e_lv0 = lv_elastance_now_, e_la0 = la_elastance_now_;
  const double e_lvh = lv_elastance_.at(t + 0.5 * h), e_lah = la_elastance_.at(t + 0.5 * h);
  const double e_lv1 = lv_elastance_.at(t + h), e_la1 = la_elastance_.at(t + h);
  auto axpy = [](const State& y, double a, const State& k) {
    State r;
    for (int i = 0; i < kSize; ++i) r[i] = y[i] + a * k[i];
    return r;
  };
  const State k1 = derivatives(y_, e_lv0, e_la0, rates, nullptr);
  const State k2 = derivatives(axpy(y_, 0.5 * h, k1), e_lvh, e_lah, rates, nullptr);
  const State k3 = derivatives(axpy(y_, 0.5 * h, k2), e_lvh, e_lah, rates, nullptr);
  const State k4 = derivatives(axpy(y_, h, k3), e_lv1, e_la1, rates, nullptr);
  State y;
  for (int i = 0; i < kSize; ++i)
    y[i] = y_[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
  if (lv_external_) y[kLv] = *at_end.lv_ml;
  if (la_external_) y[kLa] = *at_end.la_ml;
  check(y, t + h, h);
  if (mitral_inertial_ || aortic_inertial_) {
    // A closed inertial valve passes at most its leak: project the flow onto that bound.
    Readout r;
    derivatives(y, e_lv1, e_la1, rates, &r);
    if (mitral_inertial_)
      y[kMitralFlow] =
          std::max(y[kMitralFlow], mitral_floor(r.la_pressure_mmhg - r.lv_pressure_mmhg));
    if (aortic_inertial_) {
      const double dp = r.lv_pressure_mmhg - r.systemic_arterial_pressure_mmhg;
      if (dp < 0) y[kAorticFlow] = std::max(y[kAorticFlow], aortic_.closed_conductance() * dp);
    }
  }
  y_ = y;
  time_s_ = t + h;
  lv_elastance_now_ = e_lv1;
  la_elastance_now_ = e_la1;
  last_rates_ = rates;
}

Readout Circulation::readout() const {
  Readout r;
  derivatives(y_, lv_elastance_now_, la_elastance_now_, last_rates_, &r);
  r.time_s = time_s_;
  return r;
}

void Circulation::check(const State& y, double t_s, double dt_s) const {
  for (int i = 0; i < kSize; ++i) {
    if (!std::isfinite(y[i])) {
      std::ostringstream m;
      m << "non-finite value " << y[i] << " after a step of " << dt_s * 1e3
        << " ms (time step too large for these parameters?)";
      throw InstabilityError("lumped", state_name(i), t_s, m.str());
    }
  }
  for (int i : {kLv, kLa}) {
    if (y[i] < 0) {
      std::ostringstream m;
      m << "negative chamber volume " << y[i] << " ml after a step of " << dt_s * 1e3
        << " ms (time step too large for these parameters?)";
      throw InstabilityError("lumped", state_name(i), t_s, m.str());
    }
  }
}

}  // namespace systole::lumped
