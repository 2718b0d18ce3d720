#pragma once
// Unit conversions used at module boundaries. Names carry units; these are the only
// conversion factors in the code base.
namespace systole::units {
inline constexpr double kPaPerMmHg = 133.322387415;
inline constexpr double kM3PerMl = 1e-6;
inline constexpr double kSecondsPerMinute = 60.0;
inline constexpr double kMlPerLitre = 1000.0;
// Seed scales (MODEL.md §1): length d_m, velocity U_m, time d_m/U_m.
inline constexpr double kSeedLength_m = 0.024;
inline constexpr double kSeedVelocity_m_s = 0.6;
}  // namespace systole::units
