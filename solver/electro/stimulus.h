#pragma once
// Stimuli: a region of nodes and a pulse train. The region is resolved to node indices once,
// at construction; a region that matches no node is an InputError (never a silent no-op).
#include <cstdint>
#include <string>
#include <vector>

#include "solver/electro/mesh.h"

namespace systole::electro {

struct StimulusRegion {
  enum class Kind { kTagged, kSphere, kBox, kNodes };
  Kind kind = Kind::kBox;
  std::uint32_t region_bits = 0;  // kTagged: nodes carrying any of these geometry::Region bits
  Vec3 centre_mm = Vec3::Zero();  // kSphere
  double radius_mm = 0;           // kSphere
  Vec3 box_min_mm = Vec3::Zero(), box_max_mm = Vec3::Zero();  // kBox (inclusive)
  std::vector<std::int32_t> nodes;                            // kNodes
  int domain = -1;  // >= 0: only nodes of this domain (e.g. LA for the Bachmann bundle)
};

struct StimulusSpec {
  std::string name;  // for messages: "bachmann_bundle"
  StimulusRegion region;
  double amplitude_ua_per_cm2;  // transmembrane current density, > 0 depolarises
  double duration_ms;
  double start_ms;
  double period_ms;  // <= 0: a single pulse
};

// A resolved stimulus: the node list and the pulse train.
class Stimulus {
 public:
  // Throws InputError naming the stimulus when its region matches no node, or when
  // duration <= 0 or duration > period (for a periodic one).
  Stimulus(const ElectroMesh& mesh, StimulusSpec spec);
  // Amplitude (uA/cm^2) at time t_ms: the amplitude during [start + k period, + duration).
  double amplitude_at(double t_ms) const;
  const std::vector<std::int32_t>& nodes() const { return nodes_; }
  const StimulusSpec& spec() const { return spec_; }

 private:
  StimulusSpec spec_;
  std::vector<std::int32_t> nodes_;
};

}  // namespace systole::electro
