// ten Tusscher & Panfilov 2006 human ventricular myocyte (Am J Physiol Heart Circ Physiol
// 291:H1088), with the formulation of ten Tusscher, Noble, Noble & Panfilov 2004 (AJP-Heart
// 286:H1573) for the currents it keeps. Written from the published equations; constants are
// the published ones (Table 1 of the 2006 paper and its appendix). Units: mV, ms, mM, pA/pF.
// Integration as in the authors' reference code: gates by Rush–Larsen, calcium buffering by
// the quadratic rapid-buffer closure, Nai, Ki and the RyR state by forward Euler.
// Choice (ours): the stimulus current is NOT charged to Ki (the caller owns the stimulus);
// over a 10 s pacing this shifts Ki by < 0.1 mM (see docs/electro.md).
#include <cmath>
#include <vector>

#include "solver/electro/ionic/models.h"

namespace systole::electro::ionic {
namespace {

enum S : std::size_t { kKi, kNai, kCai, kCaSS, kCaSR, kRR, kXr1, kXr2, kXs, kM, kH, kJ, kD, kF, kF2, kFCaSS, kS, kR, kN };

enum P : std::size_t {
  pKo, pCao, pNao, pGNa, pGK1, pGKr, pGKs, pGto, pGCaL, pGbNa, pGbCa, pGpCa, pGpK, pknak, pknaca,
  pVmaxup, pVrel, pVleak, pVxfer, pLut, pCount
};

// The V-only gates, in this order, and their state slots.
constexpr std::size_t kGates = 11;
constexpr std::size_t kGateState[kGates] = {kM, kH, kJ, kXr1, kXr2, kXs, kR, kS, kD, kF, kF2};
struct GateRates {
  double inf[kGates];
  double tau[kGates];  // ms
};

// Steady states and time constants of the V-only gates (ten Tusscher & Panfilov 2006).
GateRates gate_rates(double V, bool epi_like) {
  GateRates g{};
  const double am = 1.0 / (1.0 + std::exp((-60.0 - V) / 5.0));
  const double bm = 0.1 / (1.0 + std::exp((V + 35.0) / 5.0)) + 0.10 / (1.0 + std::exp((V - 50.0) / 200.0));
  const double em = 1.0 + std::exp((-56.86 - V) / 9.03);
  g.inf[0] = 1.0 / (em * em);
  g.tau[0] = am * bm;
  const double eh = 1.0 + std::exp((V + 71.55) / 7.43);
  g.inf[1] = g.inf[2] = 1.0 / (eh * eh);
  if (V >= -40.0) {
    g.tau[1] = 1.0 / (0.77 / (0.13 * (1.0 + std::exp(-(V + 10.66) / 11.1))));
    g.tau[2] = 1.0 / (0.6 * std::exp(0.057 * V) / (1.0 + std::exp(-0.1 * (V + 32.0))));
  } else {
    g.tau[1] = 1.0 / (0.057 * std::exp(-(V + 80.0) / 6.8) + 2.7 * std::exp(0.079 * V) + 3.1e5 * std::exp(0.3485 * V));
    const double aj = ((-2.5428e4) * std::exp(0.2444 * V) - 6.948e-6 * std::exp(-0.04391 * V)) * (V + 37.78) /
                      (1.0 + std::exp(0.311 * (V + 79.23)));
    const double bj = 0.02424 * std::exp(-0.01052 * V) / (1.0 + std::exp(-0.1378 * (V + 40.14)));
    g.tau[2] = 1.0 / (aj + bj);
  }
  g.inf[3] = 1.0 / (1.0 + std::exp((-26.0 - V) / 7.0));
  g.tau[3] = 450.0 / (1.0 + std::exp((-45.0 - V) / 10.0)) * 6.0 / (1.0 + std::exp((V + 30.0) / 11.5));
  g.inf[4] = 1.0 / (1.0 + std::exp((V + 88.0) / 24.0));
  g.tau[4] = 3.0 / (1.0 + std::exp((-60.0 - V) / 20.0)) * 1.12 / (1.0 + std::exp((V - 60.0) / 20.0));
  g.inf[5] = 1.0 / (1.0 + std::exp((-5.0 - V) / 14.0));
  g.tau[5] = 1400.0 / std::sqrt(1.0 + std::exp((5.0 - V) / 6.0)) * (1.0 / (1.0 + std::exp((V - 35.0) / 15.0))) + 80.0;
  g.inf[6] = 1.0 / (1.0 + std::exp((20.0 - V) / 6.0));
  g.tau[6] = 9.5 * std::exp(-(V + 40.0) * (V + 40.0) / 1800.0) + 0.8;
  if (epi_like) {
    g.inf[7] = 1.0 / (1.0 + std::exp((V + 20.0) / 5.0));
    g.tau[7] = 85.0 * std::exp(-(V + 45.0) * (V + 45.0) / 320.0) + 5.0 / (1.0 + std::exp((V - 20.0) / 5.0)) + 3.0;
  } else {
    g.inf[7] = 1.0 / (1.0 + std::exp((V + 28.0) / 5.0));
    g.tau[7] = 1000.0 * std::exp(-(V + 67.0) * (V + 67.0) / 1000.0) + 8.0;
  }
  g.inf[8] = 1.0 / (1.0 + std::exp((-8.0 - V) / 7.5));
  g.tau[8] = (1.4 / (1.0 + std::exp((-35.0 - V) / 13.0)) + 0.25) * (1.4 / (1.0 + std::exp((V + 5.0) / 5.0))) +
             1.0 / (1.0 + std::exp((50.0 - V) / 20.0));
  g.inf[9] = 1.0 / (1.0 + std::exp((V + 20.0) / 7.0));
  g.tau[9] = 1102.5 * std::exp(-(V + 27.0) * (V + 27.0) / 225.0) + 200.0 / (1.0 + std::exp((13.0 - V) / 10.0)) +
             180.0 / (1.0 + std::exp((V + 30.0) / 10.0)) + 20.0;
  g.inf[10] = 0.67 / (1.0 + std::exp((V + 35.0) / 7.0)) + 0.33;
  g.tau[10] = 600.0 * std::exp(-(V + 25.0) * (V + 25.0) / 170.0) + 31.0 / (1.0 + std::exp((25.0 - V) / 10.0)) +
              16.0 / (1.0 + std::exp((V + 30.0) / 10.0));
  return g;
}

// V-only factors of the currents: INaK and IpK rectification, the INaCa exponentials, and the
// two GHK coefficients of ICaL (ICaL / (GCaL d f f2 fCaSS) = CaSS c_ss - Cao c_o).
constexpr std::size_t kFactors = 7;
struct CurrentFactors {
  double v[kFactors];  // nak, pk, e_n, e_n1, sat, c_ss, c_o
};
CurrentFactors current_factors(double V) {
  constexpr double R = 8314.472, F = 96485.3415, T = 310.0, FRT = F / (R * T);
  constexpr double ksat = 0.1, nexp = 0.35;
  CurrentFactors c{};
  c.v[0] = 1.0 / (1.0 + 0.1245 * std::exp(-0.1 * V * FRT) + 0.0353 * std::exp(-V * FRT));
  c.v[1] = 1.0 / (1.0 + std::exp((25.0 - V) / 5.98));
  c.v[2] = std::exp(nexp * V * FRT);
  c.v[3] = std::exp((nexp - 1.0) * V * FRT);
  c.v[4] = 1.0 / (1.0 + ksat * c.v[3]);
  const double v15 = (V - 15.0) * FRT;
  if (std::abs(v15) < 1e-6) {  // the removable singularity of the GHK flux at V = 15 mV
    c.v[5] = 0.5 * F;
    c.v[6] = 2.0 * F;
  } else {
    const double e2 = std::exp(2.0 * v15);
    c.v[5] = F * v15 * e2 / (e2 - 1.0);
    c.v[6] = 4.0 * F * v15 / (e2 - 1.0);
  }
  return c;
}

// Lookup table of (x_inf, exp(-dt / tau)) for the V-only gates, linear in V (as openCARP's
// LUTs; ours: range and resolution). Outside the range the exact functions are used.
constexpr double kTableMinMv = -120.0, kTableMaxMv = 80.0, kTableStepMv = 0.01;
constexpr std::size_t kRow = 2 * kGates + kFactors;

class Ttp06 final : public CellModel {
 public:
  Ttp06(std::size_t n, Ttp06Cell cell)
      : CellModel(n,
                  {{"Ko", 5.4, "mM", "extracellular K+"},
                   {"Cao", 2.0, "mM", "extracellular Ca2+"},
                   {"Nao", 140.0, "mM", "extracellular Na+"},
                   {"GNa", 14.838, "nS/pF", "fast Na+ conductance"},
                   {"GK1", 5.405, "nS/pF", "inward rectifier conductance"},
                   {"GKr", 0.153, "nS/pF", "rapid delayed rectifier conductance"},
                   {"GKs", cell == Ttp06Cell::kMid ? 0.098 : 0.392, "nS/pF", "slow delayed rectifier (M cell 0.098)"},
                   {"Gto", cell == Ttp06Cell::kEndo ? 0.073 : 0.294, "nS/pF", "transient outward (endo 0.073)"},
                   {"GCaL", 3.980e-5, "cm/(ms uF)", "L-type Ca2+ permeability"},
                   {"GbNa", 2.9e-4, "nS/pF", "background Na+"},
                   {"GbCa", 5.92e-4, "nS/pF", "background Ca2+"},
                   {"GpCa", 0.1238, "pA/pF", "sarcolemmal Ca2+ pump"},
                   {"GpK", 0.0146, "nS/pF", "plateau K+"},
                   {"knak", 2.724, "pA/pF", "Na+/K+ pump maximum"},
                   {"knaca", 1000.0, "pA/pF", "Na+/Ca2+ exchanger maximum"},
                   {"Vmaxup", 0.006375, "mM/ms", "SERCA maximum"},
                   {"Vrel", 0.102, "1/ms", "RyR release rate"},
                   {"Vleak", 3.6e-4, "1/ms", "SR leak"},
                   {"Vxfer", 3.8e-3, "1/ms", "subspace -> cytoplasm transfer"},
                   {"lookup_table", 1.0, "1", "1: V-only gates from a 0.01 mV lookup table (ours), 0: exact"}}),
        cell_(cell) {
    allocate_state();
  }
  std::string_view name() const override {
    return cell_ == Ttp06Cell::kEndo ? "ttp06_endo" : cell_ == Ttp06Cell::kMid ? "ttp06_mid" : "ttp06_epi";
  }
  std::vector<std::string> state_names() const override {
    return {"Ki", "Nai", "Cai", "CaSS", "CaSR", "RR", "Xr1", "Xr2", "Xs", "m", "h", "j",
            "d",  "f",   "f2",  "fCaSS", "s",   "r"};
  }
  double resting_potential_mv() const override { return -85.23; }
  double peak_potential_mv() const override { return 40.0; }
  // Vm is explicit: the fast Na+ current gives |dIion/dVm| ~ GNa m^3 h j ~ 15/ms at the
  // upstroke -> Euler limit ~ 0.13 ms. Declared 0.1 ms (ours).
  double max_stable_dt_ms() const override { return 0.1; }
  // Initial state of the authors' code (epicardial, after pacing); the same for all three.
  std::vector<double> initial_state() const override {
    return {136.89, 8.604, 0.000126, 0.00036, 3.64, 0.9073, 0.00621, 0.4712, 0.0095,
            0.00172, 0.7444, 0.7045, 3.373e-5, 0.7888, 0.9755, 0.9953, 0.999998, 2.42e-8};
  }

  void compute(NodeRange range, double dt, const double* vm, double* iion) override {
    // Fixed constants (Table 1 of ten Tusscher & Panfilov 2006).
    constexpr double R = 8314.472, F = 96485.3415, T = 310.0, RTONF = R * T / F;
    constexpr double Cm = 0.185;                                  // uF
    constexpr double Vc = 0.016404, Vsr = 0.001094, Vss = 5.468e-5;  // uL
    constexpr double Bufc = 0.2, Kbufc = 0.001, Bufsr = 10.0, Kbufsr = 0.3, Bufss = 0.4, Kbufss = 0.00025;
    constexpr double Kup = 0.00025, k1p = 0.15, k2p = 0.045, k3 = 0.060, k4 = 0.005, EC = 1.5;
    constexpr double maxsr = 2.5, minsr = 1.0;
    constexpr double pKNa = 0.03, KmK = 1.0, KmNa = 40.0, KmNai = 87.5, KmCa = 1.38, KpCa = 0.0005;
    const double Ko = p(pKo), Cao = p(pCao), Nao = p(pNao);
    const double inv_VcF = 1.0 / (Vc * F), inv_2VcF = 1.0 / (2.0 * Vc * F), inv_2VssF = 1.0 / (2.0 * Vss * F);
    const bool epi_like = cell_ != Ttp06Cell::kEndo;
    const bool use_table = p(pLut) != 0.0;
    if (use_table && dt != table_dt_ms_) build_table(dt, epi_like);
    auto& x = state_;

    for (std::size_t i = range.begin; i < range.end; ++i) {
      const double V = vm[i];
      double& Ki = x[kKi][i];
      double& Nai = x[kNai][i];
      double& Cai = x[kCai][i];
      double& CaSS = x[kCaSS][i];
      double& CaSR = x[kCaSR][i];
      double& RR = x[kRR][i];

      // --- reversal potentials ---
      const double Ek = RTONF * std::log(Ko / Ki);
      const double Ena = RTONF * std::log(Nao / Nai);
      const double Eks = RTONF * std::log((Ko + pKNa * Nao) / (Ki + pKNa * Nai));
      const double Eca = 0.5 * RTONF * std::log(Cao / Cai);

      // --- membrane currents (pA/pF) ---
      const double ak1 = 0.1 / (1.0 + std::exp(0.06 * (V - Ek - 200.0)));
      const double bk1 = (3.0 * std::exp(0.0002 * (V - Ek + 100.0)) + std::exp(0.1 * (V - Ek - 10.0))) /
                         (1.0 + std::exp(-0.5 * (V - Ek)));
      const double IK1 = p(pGK1) * ak1 / (ak1 + bk1) * (V - Ek);
      const double INa = p(pGNa) * x[kM][i] * x[kM][i] * x[kM][i] * x[kH][i] * x[kJ][i] * (V - Ena);
      // V-only factors: interpolated from the table row (w) or computed exactly.
      const bool in_table = use_table && V > kTableMinMv && V < kTableMaxMv;
      const double* a = nullptr;
      const double* b = nullptr;
      double w = 0.0;
      CurrentFactors cf{};
      if (in_table) {
        const double u = (V - kTableMinMv) / kTableStepMv;
        const auto row = static_cast<std::size_t>(u);
        w = u - static_cast<double>(row);
        a = &table_[row * kRow];
        b = a + kRow;
        for (std::size_t k = 0; k < kFactors; ++k)
          cf.v[k] = a[2 * kGates + k] + w * (b[2 * kGates + k] - a[2 * kGates + k]);
      } else {
        cf = current_factors(V);
      }
      const double ical_ghk = CaSS * cf.v[5] - Cao * cf.v[6];
      const double ICaL = p(pGCaL) * x[kD][i] * x[kF][i] * x[kF2][i] * x[kFCaSS][i] * ical_ghk;
      const double Ito = p(pGto) * x[kR][i] * x[kS][i] * (V - Ek);
      const double IKr = p(pGKr) * std::sqrt(Ko / 5.4) * x[kXr1][i] * x[kXr2][i] * (V - Ek);
      const double IKs = p(pGKs) * x[kXs][i] * x[kXs][i] * (V - Eks);
      const double INaCa = p(pknaca) / ((KmNai * KmNai * KmNai + Nao * Nao * Nao) * (KmCa + Cao)) * cf.v[4] *
                           (cf.v[2] * Nai * Nai * Nai * Cao - cf.v[3] * Nao * Nao * Nao * Cai * 2.5);
      const double INaK = p(pknak) * Ko / (Ko + KmK) * Nai / (Nai + KmNa) * cf.v[0];
      const double IpCa = p(pGpCa) * Cai / (KpCa + Cai);
      const double IpK = p(pGpK) * cf.v[1] * (V - Ek);
      const double IbNa = p(pGbNa) * (V - Ena);
      const double IbCa = p(pGbCa) * (V - Eca);
      iion[i] = IKr + IKs + IK1 + Ito + INa + IbNa + ICaL + IbCa + INaK + INaCa + IpCa + IpK;

      // --- calcium handling (rapid buffering closed form) ---
      const double kCaSR = maxsr - (maxsr - minsr) / (1.0 + (EC / CaSR) * (EC / CaSR));
      const double k1 = k1p / kCaSR, k2 = k2p * kCaSR;
      RR += dt * (k4 * (1.0 - RR) - k2 * CaSS * RR);
      const double OO = k1 * CaSS * CaSS * RR / (k3 + k1 * CaSS * CaSS);
      const double Irel = p(pVrel) * OO * (CaSR - CaSS);
      const double Ileak = p(pVleak) * (CaSR - Cai);
      const double Iup = p(pVmaxup) / (1.0 + (Kup * Kup) / (Cai * Cai));
      const double Ixfer = p(pVxfer) * (CaSS - Cai);
      {
        const double csqn = Bufsr * CaSR / (CaSR + Kbufsr);
        const double d = dt * (Iup - Irel - Ileak);
        const double b = Bufsr - csqn - d - CaSR + Kbufsr, c = Kbufsr * (csqn + d + CaSR);
        CaSR = (std::sqrt(b * b + 4.0 * c) - b) / 2.0;
      }
      {
        const double buf = Bufss * CaSS / (CaSS + Kbufss);
        const double d = dt * (-Ixfer * (Vc / Vss) + Irel * (Vsr / Vss) - ICaL * inv_2VssF * Cm);
        const double b = Bufss - buf - d - CaSS + Kbufss, c = Kbufss * (buf + d + CaSS);
        CaSS = (std::sqrt(b * b + 4.0 * c) - b) / 2.0;
      }
      {
        const double buf = Bufc * Cai / (Cai + Kbufc);
        const double d = dt * (-(IbCa + IpCa - 2.0 * INaCa) * inv_2VcF * Cm - (Iup - Ileak) * (Vsr / Vc) + Ixfer);
        const double b = Bufc - buf - d - Cai + Kbufc, c = Kbufc * (buf + d + Cai);
        Cai = (std::sqrt(b * b + 4.0 * c) - b) / 2.0;
      }
      Nai += -dt * (INa + IbNa + 3.0 * INaK + 3.0 * INaCa) * inv_VcF * Cm;
      Ki += -dt * (IK1 + Ito + IKr + IKs - 2.0 * INaK + IpK) * inv_VcF * Cm;

      // --- gates (Rush–Larsen; the V-only gates from the table when enabled) ---
      if (in_table) {
        for (std::size_t g = 0; g < kGates; ++g) {
          const double inf = a[2 * g] + w * (b[2 * g] - a[2 * g]);
          const double decay = a[2 * g + 1] + w * (b[2 * g + 1] - a[2 * g + 1]);
          double& xg = x[kGateState[g]][i];
          xg = inf - (inf - xg) * decay;
        }
      } else {
        const GateRates r = gate_rates(V, epi_like);
        for (std::size_t g = 0; g < kGates; ++g) {
          double& xg = x[kGateState[g]][i];
          xg = rush_larsen(xg, r.inf[g], r.tau[g], dt);
        }
      }
      const double css = (CaSS / 0.05) * (CaSS / 0.05);
      x[kFCaSS][i] = rush_larsen(x[kFCaSS][i], 0.6 / (1.0 + css) + 0.4, 80.0 / (1.0 + css) + 2.0, dt);
    }
  }

 private:
  void build_table(double dt, bool epi_like) {
    const auto rows = static_cast<std::size_t>(std::lround((kTableMaxMv - kTableMinMv) / kTableStepMv)) + 2;
    table_.assign(rows * kRow, 0.0);
    for (std::size_t r = 0; r < rows; ++r) {
      const double V = kTableMinMv + static_cast<double>(r) * kTableStepMv;
      const GateRates g = gate_rates(V, epi_like);
      for (std::size_t k = 0; k < kGates; ++k) {
        table_[r * kRow + 2 * k] = g.inf[k];
        table_[r * kRow + 2 * k + 1] = std::exp(-dt / g.tau[k]);
      }
      const CurrentFactors c = current_factors(V);
      for (std::size_t k = 0; k < kFactors; ++k) table_[r * kRow + 2 * kGates + k] = c.v[k];
    }
    table_dt_ms_ = dt;
  }

  Ttp06Cell cell_;
  std::vector<double> table_;
  double table_dt_ms_ = -1.0;
};

}  // namespace

std::unique_ptr<CellModel> make_ttp06(std::size_t n, Ttp06Cell cell) { return std::make_unique<Ttp06>(n, cell); }

}  // namespace systole::electro::ionic
