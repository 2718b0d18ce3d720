// Unit tests of validation at submit (issue 59, item 4): the nearest-name suggestions
// (solver/core/nearest_names.h), scenes fsi/fsei's rules in config (solver/config/fsei_rules.h),
// and proto3 JSON with every unknown key named (proto/bridge/json_fields.h).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "proto/bridge/json_fields.h"
#include "proto/bridge/scenario_bridge.h"
#include "solver/config/fsei_rules.h"
#include "solver/config/parameter_table.h"
#include "solver/config/removed_fields.h"
#include "solver/config/scenario.h"
#include "solver/core/errors.h"
#include "solver/core/nearest_names.h"
#include "systole/v1/campaign.pb.h"
#include "systole/v1/service.pb.h"

namespace systole {
namespace {

using nlohmann::json;

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// --- nearest names ------------------------------------------------------------------------

TEST(NearestNames, TyposSwapsCaseAndAMissingUnitAreNear) {
  const std::vector<std::string> fields{"heart_rate_bpm", "beats", "av_delay_ms", "coupling_order", "scene"};
  EXPECT_EQ(nearest_names("coupling_ordr", fields), std::vector<std::string>{"coupling_order"});
  EXPECT_EQ(nearest_names("heart_rate_bmp", fields), std::vector<std::string>{"heart_rate_bpm"});  // a swap
  EXPECT_EQ(nearest_names("Scnee", fields), std::vector<std::string>{"scene"});                    // case, a swap
  EXPECT_EQ(nearest_names("heart_rate", fields), std::vector<std::string>{"heart_rate_bpm"});      // unit left off
  EXPECT_EQ(nearest_names("av_delay_ms_ms", fields), std::vector<std::string>{"av_delay_ms"});    // unit added
  EXPECT_TRUE(nearest_names("resistance", fields).empty());
  EXPECT_TRUE(nearest_names("beats", fields).empty());  // the name itself is not a suggestion
  EXPECT_EQ(did_you_mean("beets", fields), "did you mean 'beats'? ");
  EXPECT_EQ(did_you_mean("nx", {"box", "nx_", "ny", "nz"}), "did you mean 'nx_', 'ny' or 'nz'? ");
  EXPECT_EQ(did_you_mean("resistance", fields), "");
}

// --- scenes fsi/fsei: every rule that depends only on the scenario, at parsing ---------------

std::string error_of(json document) {
  try {
    (void)config::parse_scenario(document);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// A scenario of `scene` on the table's own defaults (fsei.defaults = seed) with `fsei` and more.
json seed(const std::string& scene, json fsei, json more = json::object()) {
  json doc = more;
  doc["scene"] = scene;
  doc["fsei"] = fsei;
  doc["fsei"]["defaults"] = "seed";
  return doc;
}

// Each rule: the bad scenario is refused naming every field it involves; the good one parses.
struct RuleCase {
  const char* name;
  json bad, good;
  std::vector<std::string> named;
};

TEST(FseiRules, EachRuleRefusesTheBadScenarioNamingItsFieldsAndAcceptsTheGoodOne) {
  const std::vector<RuleCase> cases{
      {"pre-stress share without the pre-stress", seed("fsi", {{"aorta", {{"prestress_fraction", 0.25}}}}),
       seed("fsi", {{"aorta", {{"prestress_fraction", 0.25}, {"pretension", "prestress"}}}}),
       {"fsei.aorta.prestress_fraction = 0.25", "fsei.aorta.pretension = \"prestress\"", "got \"outer_load\""}},
      {"shells first with loose coupling", seed("fsi", {{"coupling_order", "structure_first"}}),
       seed("fsi", {{"coupling_order", "structure_first"}, {"strong_coupling", true}}),
       {"fsei.coupling_order = \"structure_first\" needs fsei.strong_coupling = true"}},
      {"the linear guess in the fluid-first order", seed("fsi", {{"first_pass_predictor", "linear"}, {"strong_coupling", true}}),
       seed("fsi", {{"first_pass_predictor", "linear"}, {"strong_coupling", true}, {"coupling_order", "structure_first"}}),
       {"fsei.first_pass_predictor = \"linear\" needs fsei.coupling_order = \"structure_first\"", "got \"fluid_first\""}},
      {"fluid steps per interval with fixed intervals", seed("fsi", {{"fluid_steps_per_interval", 2}}),
       seed("fsi", {{"fluid_steps_per_interval", 2}, {"sync_interval", "fluid_step"}}),
       {"fsei.fluid_steps_per_interval = 2 needs fsei.sync_interval = \"fluid_step\""}},
      {"the limiter's window without the limiter",
       seed("fsi", json::object(), {{"structure", {{"mitral_limiter", false}, {"mitral_limiter_end_phase", 0.4}}}}),
       seed("fsi", json::object(), {{"structure", {{"mitral_limiter", true}, {"mitral_limiter_end_phase", 0.4}}}}),
       {"structure.mitral_limiter_end_phase = 0.4", "needs structure.mitral_limiter = true"}},
      {"fsei: EP steps per synchronisation step",
       seed("fsei", {{"sync_step_ms", 0.075}}, {{"electro", {{"time_step_ms", 0.05}}}}),
       seed("fsei", {{"sync_step_ms", 0.1}}, {{"electro", {{"time_step_ms", 0.05}}}}),
       {"fsei.sync_step_ms = 0.075 ms must be a whole multiple of electro.time_step_ms = 0.05 ms"}},
      {"fsei: the EP's mesh", seed("fsei", json::object(), {{"electro", {{"mesh", "slab"}}}}),
       seed("fsei", json::object(), {{"electro", {{"mesh", "left_heart"}}}}),
       {"electro.mesh = \"slab\" is not allowed in scene fsei; allowed: left_heart"}},
      {"a grid too coarse for the valves",
       seed("fsi", {{"resolution", "custom"}}, {{"fluid", {{"nx", 33}, {"ny", 33}, {"nz", 37}}}}),
       seed("fsi", {{"resolution", "custom"}}, {{"fluid", {{"nx", 97}, {"ny", 97}, {"nz", 109}}}}),
       {"fsei.resolution = \"custom\" (fluid.nx/ny/nz: 33 x 33 x 37 points", "too coarse for the valves",
        "geometry.aortic_diameter_mm = 19", "at least 8 are needed", "at least 41 x 41 x 60 points"}},
      {"a probe smaller than a cell", seed("fsi", {{"probe_radius_mm", 1}}), seed("fsi", {{"probe_radius_mm", 1.5}}),
       {"fsei.probe_radius_mm = 1 is less than half a grid cell's diagonal (1.43", "fsei.resolution = \"coarse\"",
        "allowed: at least 1.43"}},
  };
  for (const RuleCase& c : cases) {
    const std::string bad = error_of(c.bad);
    EXPECT_TRUE(contains(bad, "invalid scenario: ")) << c.name << ": one problem, got " << bad;
    for (const auto& part : c.named) EXPECT_TRUE(contains(bad, part)) << c.name << ": " << bad;
    EXPECT_EQ(error_of(c.good), "") << c.name;
  }
}

// The issue's example: seed's loose coupling with the shells-first order, both fields named.
TEST(FseiRules, TheIssuesExampleNamesBothFields) {
  EXPECT_EQ(error_of({{"scene", "fsi"}, {"fsei", {{"defaults", "seed"}, {"coupling_order", "structure_first"}}}}),
            "invalid scenario: fsei.coupling_order = \"structure_first\" needs fsei.strong_coupling = true (its point is "
            "strong coupling's first-pass check; got false); with loose coupling use \"fluid_first\"");
  EXPECT_FALSE(config::parse_scenario({{"scene", "fsi"}, {"fsei", {{"defaults", "seed"}}}}).fsei.strong_coupling);
}

TEST(FseiRules, EveryViolatedRuleIsReportedAtOnce) {
  const std::string all = error_of(seed("fsei",
                                        {{"aorta", {{"prestress_fraction", 0.5}}}, {"coupling_order", "structure_first"},
                                         {"fluid_steps_per_interval", 3}, {"sync_step_ms", 0.075}, {"probe_radius_mm", 0.5}},
                                        {{"electro", {{"mesh", "sheet"}}}}));
  EXPECT_TRUE(contains(all, "invalid scenario (6 problems)")) << all;
  for (const char* field : {"fsei.aorta.prestress_fraction", "fsei.coupling_order", "fsei.fluid_steps_per_interval",
                            "fsei.sync_step_ms", "electro.mesh", "fsei.probe_radius_mm"})
    EXPECT_TRUE(contains(all, field)) << field << ": " << all;
}

// The calibrated layer (and the examples, config_test) satisfy every rule at every preset; the
// rules are scenes fsi/fsei's only.
TEST(FseiRules, CalibratedDefaultsPassAtEveryPresetAndOtherScenesAreUntouched) {
  for (const char* scene : {"fsi", "fsei"})
    for (const char* preset : {"coarse", "basic", "fine", "very_fine"})
      EXPECT_EQ(error_of({{"scene", scene}, {"fsei", {{"resolution", preset}}}}), "") << scene << " " << preset;
  EXPECT_EQ(error_of({{"scene", "lumped"}, {"fsei", {{"coupling_order", "structure_first"}, {"probe_radius_mm", 0.1}}}}),
            "");
}

TEST(FseiRules, ElectromechanicsStepsAndMeshAreCheckedAtParsing) {
  const std::string step = error_of({{"scene", "electromechanics"},
                                     {"electromechanics", {{"sync_step_ms", 0.075}}},
                                     {"electro", {{"time_step_ms", 0.05}}}});
  EXPECT_TRUE(contains(step, "electromechanics.sync_step_ms = 0.075 ms must be a whole multiple of "
                             "electro.time_step_ms = 0.05 ms"))
      << step;
  const std::string mesh = error_of({{"scene", "electromechanics"}, {"electro", {{"mesh", "slab"}}}});
  EXPECT_TRUE(contains(mesh, "electro.mesh = \"slab\" is not allowed in scene electromechanics")) << mesh;
  EXPECT_EQ(error_of({{"scene", "electromechanics"}}), "");
}

TEST(FseiRules, GridPointsOfThePresetsAndTheErrorForAnUnknownOne) {
  auto points = [](const char* preset, double box_z_mm) {
    return config::fsei_grid_points(
        config::parse_scenario({{"scene", "fsi"}, {"fsei", {{"resolution", preset}}}, {"fluid", {{"box_z_mm", box_z_mm}}}}));
  };
  EXPECT_EQ(points("coarse", 140).nx, 65);
  EXPECT_EQ(points("coarse", 140).nz, 73);
  EXPECT_EQ(points("coarse", 180).nz, 93);
  EXPECT_EQ(points("basic", 180).nz, 186);
  EXPECT_EQ(points("fine", 140).nz, 257);
  EXPECT_EQ(points("very_fine", 140).nx, 257);
  config::Scenario s = config::default_scenario();
  s.fsei.resolution = "huge";
  try {
    (void)config::fsei_grid_points(s);
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "fsei.resolution = \"huge\" is not a preset; allowed: coarse, basic, fine, very_fine, custom");
  }
}

TEST(ConfigUnknownFields, EachGetsTheNearestKnownNames) {
  const std::string e = error_of({{"heart_rate_bmp", 70}, {"fsei", {{"coupling_ordr", "fluid_first"}}}});
  EXPECT_TRUE(contains(e, "unknown field 'heart_rate_bmp'; did you mean 'heart_rate_bpm'? known fields: ")) << e;
  EXPECT_TRUE(contains(e, "unknown field 'fsei.coupling_ordr'; did you mean 'coupling_order'? known fields of fsei: "))
      << e;
  nlohmann::json doc = json::object();
  try {
    config::apply_override(doc, "fsei.strong_couplng=true");
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& x) {
    EXPECT_TRUE(contains(x.what(), "did you mean 'strong_coupling'?")) << x.what();
  }
  try {
    config::apply_override(doc, "lumpd.lv.emax_mmhg_per_ml=2");
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& x) {
    EXPECT_TRUE(contains(x.what(), "did you mean 'lumped.lv.emax_mmhg_per_ml'")) << x.what();
  }
}

// --- proto3 JSON: every unknown key, with its path and the nearest allowed names ------------

TEST(JsonFields, EveryMisspeltKeyIsNamedWithItsPathAndASuggestion) {
  v1::SubmitJobRequest request;
  const bridge::JsonParse parse = bridge::parse_json_message(
      R"({"scenario": {"scene": "fsi", "heart_rate_bmp": 70,
                       "fsei": {"coupling_ordr": "structure_first", "strongCouplng": true}},
          "priorty": 3})",
      request);
  EXPECT_TRUE(parse.parsed);
  ASSERT_EQ(parse.problems.size(), 4u) << ::testing::PrintToString(parse.problems);
  const std::string all = ::testing::PrintToString(parse.problems);
  EXPECT_TRUE(contains(all, "unknown field 'scenario.heart_rate_bmp'; did you mean 'heart_rate_bpm'? allowed: ")) << all;
  EXPECT_TRUE(contains(all, "unknown field 'scenario.fsei.coupling_ordr'; did you mean 'coupling_order'? allowed: ")) << all;
  EXPECT_TRUE(contains(all, "unknown field 'scenario.fsei.strongCouplng'; did you mean 'strongCoupling'? allowed: ")) << all;
  EXPECT_TRUE(contains(all, "unknown field 'priorty'; did you mean 'priority'? allowed: ")) << all;
  // the known fields parsed, in either spelling
  EXPECT_EQ(request.scenario().scene(), "fsi");
}

TEST(JsonFields, RepeatedMessagesAndCamelCaseAndTypeErrors) {
  v1::SubmitCampaignRequest campaign;
  const auto spec = bridge::parse_json_message(
      R"({"spec": {"baseScenario": {"heartRateBpm": 80},
                   "parameters": [{"path": "beats", "uniform": {"min": 1, "max": 2}},
                                  {"path": "heart_rate_bpm", "unifrom": {"min": 60, "max": 80}}],
                   "samples": 4}})",
      campaign);
  ASSERT_EQ(spec.problems.size(), 1u) << ::testing::PrintToString(spec.problems);
  EXPECT_TRUE(contains(spec.problems[0], "unknown field 'spec.parameters[1].unifrom'; did you mean 'uniform'?"))
      << spec.problems[0];
  EXPECT_EQ(campaign.spec().base_scenario().heart_rate_bpm(), 80);
  // a value of the wrong type: protobuf's own message, with the unknown keys still named
  v1::SubmitJobRequest job;
  const auto typed = bridge::parse_json_message(R"({"scenario": {"heart_rate_bpm": "fast", "beatz": 2}})", job);
  EXPECT_FALSE(typed.parsed);
  ASSERT_EQ(typed.problems.size(), 2u) << ::testing::PrintToString(typed.problems);
  EXPECT_TRUE(contains(typed.problems[0], "scenario.beatz")) << typed.problems[0];
  // malformed JSON and a document that is not an object: one problem each
  EXPECT_EQ(bridge::parse_json_message("{\"scenario\": {", job).problems.size(), 1u);
  EXPECT_TRUE(contains(bridge::parse_json_message("[1]", job).problems.at(0), "must be a JSON object")) << "[1]";
  const auto empty = bridge::parse_json_message("", job);
  EXPECT_TRUE(empty.parsed && empty.problems.empty());
}

TEST(JsonFields, AScenarioFilesUnknownKeysComeWithItsOtherProblems) {
  try {
    (void)bridge::scenario_proto_from_json_text(
        R"({"scene": "fsi", "fsei": {"defaults": "seed", "coupling_order": "structure_first", "strong_couplng": true}})");
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_TRUE(contains(m, "invalid scenario JSON (2 problems)")) << m;
    EXPECT_TRUE(contains(m, "unknown field 'fsei.strong_couplng'; did you mean 'strong_coupling'?")) << m;
    EXPECT_TRUE(contains(m, "fsei.coupling_order = \"structure_first\" needs fsei.strong_coupling = true")) << m;
  }
}

// --- removed and moved fields (solver/config/removed_fields.h) --------------------------------

// A scenario naming a removed or moved field is told what happened and why, in config's JSON walk,
// in --set and in the proto JSON check the REST gateway and scenario files use.
TEST(RemovedFields, EachIsNamedWithWhatHappenedInParsingSetAndProtoJson) {
  const std::string e = error_of({{"scene", "fsi"}, {"fsei", {{"forcing_row_sum_scaling", true}, {"forcing_kernel", "mls"}}}});
  EXPECT_TRUE(contains(e, "invalid scenario (2 problems)")) << e;
  EXPECT_TRUE(contains(e, "fsei.forcing_row_sum_scaling was removed: refuted: ")) << e;
  EXPECT_TRUE(contains(e, "0.186 s against 0.229 s")) << e;
  EXPECT_TRUE(contains(e, "; remove it from the scenario")) << e;
  EXPECT_TRUE(contains(e, "fsei.forcing_kernel moved to fsei.forcing.kernel (")) << e;
  EXPECT_TRUE(contains(e, "rename it in the scenario")) << e;
  json doc = json::object();
  try {
    config::apply_override(doc, "fsei.marker_tiling=mean_edge");
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& x) {
    EXPECT_TRUE(contains(x.what(), "--set: fsei.marker_tiling was removed: ")) << x.what();
  }
  try {
    config::apply_override(doc, "fsei.aortic_pressure_mmhg=70");
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& x) {
    EXPECT_TRUE(contains(x.what(), "fsei.aortic_pressure_mmhg moved to fsei.aorta.ground_pressure_mmhg")) << x.what();
  }
  // every entry: a moved field's new path is a parameter, a removed one is not, and each has a reason
  for (const config::RemovedField& f : config::removed_fields()) {
    EXPECT_EQ(config::find_parameter(f.path), nullptr) << f.path;
    EXPECT_FALSE(f.why.empty()) << f.path;
    if (!f.moved_to.empty()) EXPECT_NE(config::find_parameter(f.moved_to), nullptr) << f.moved_to;
    else EXPECT_FALSE(f.only_value.empty()) << f.path;
  }
  // proto3 JSON: inside a request and in a scenario file, either spelling
  v1::SubmitJobRequest request;
  const bridge::JsonParse parse = bridge::parse_json_message(
      R"({"scenario": {"scene": "fsi", "fsei": {"forcingCarryOverFactor": 0.9, "aortic_pretension": "prestress"}}})",
      request);
  ASSERT_EQ(parse.problems.size(), 2u) << ::testing::PrintToString(parse.problems);
  EXPECT_TRUE(contains(parse.problems[0], "scenario.fsei.forcingCarryOverFactor: fsei.forcing_carry_over_factor was removed: "))
      << parse.problems[0];
  EXPECT_TRUE(contains(parse.problems[1], "scenario.fsei.aortic_pretension: fsei.aortic_pretension moved to fsei.aorta.pretension"))
      << parse.problems[1];
  try {
    (void)bridge::scenario_proto_from_json_text(R"({"scene": "fsi", "fsei": {"stencil_tolerance_cells": 0}})");
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& x) {
    EXPECT_TRUE(contains(x.what(), "fsei.stencil_tolerance_cells was removed: unused")) << x.what();
  }
  // the new paths parse, through both
  EXPECT_EQ(error_of({{"scene", "fsi"}, {"fsei", {{"forcing", {{"kernel", "mls"}}}, {"aorta", {{"pretension", "prestress"}}}}}}), "");
  const auto ok = bridge::scenario_proto_from_json_text(R"({"scene": "fsi", "fsei": {"forcing": {"kernel": "mls"}}})");
  EXPECT_EQ(ok.fsei().forcing().kernel(), "mls");
}

// message Fsei keeps at most 20 fields (issue 59, item 5): the forcing and the aorta are groups.
TEST(RemovedFields, TheFseiMessageHasAtMostTwentyFields) {
  EXPECT_LE(v1::Fsei::descriptor()->field_count(), 20);
}

}  // namespace
}  // namespace systole
