// Unit tests of solver/config: defaults, validation messages, overrides, and the proto/table
// consistency that keeps proto/systole/v1/scenario.proto and parameter_table.cc in step.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include <google/protobuf/descriptor.h>

#include "proto/bridge/scenario_bridge.h"
#include "solver/config/parameter_table.h"
#include "solver/config/scenario.h"
#include "solver/core/errors.h"

namespace systole::config {
namespace {

std::string error_of(const nlohmann::json& document) {
  try {
    (void)parse_scenario(document);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Config, DefaultsAreTheSeedsHealthyHeart) {
  const Scenario s = default_scenario();
  EXPECT_EQ(s.scene, "lumped");
  EXPECT_DOUBLE_EQ(s.heart_rate_bpm, 70);
  EXPECT_DOUBLE_EQ(s.av_delay_ms, 100);
  EXPECT_DOUBLE_EQ(s.tissue.lv.fung_c_pa, 13.3);
  EXPECT_DOUBLE_EQ(s.tissue.aorta.fung_c_pa, 11.3);
  // the leaflets' c: the seed's 9.7 in units of rho U^2 (ours, docs/fsei.md)
  EXPECT_DOUBLE_EQ(s.tissue.mitral_leaflets.fung_c_pa, 3702);
  EXPECT_DOUBLE_EQ(s.tissue.aortic_leaflets.fung_c_pa, 3702);
  EXPECT_DOUBLE_EQ(s.tissue.la.fung_c_pa, 12.1);
  EXPECT_DOUBLE_EQ(s.tissue.lv.alpha_f, 49.56);
  EXPECT_DOUBLE_EQ(s.tissue.lv.alpha_c, 5.29);
  EXPECT_DOUBLE_EQ(s.tissue.density_g_per_ml, 1.05);
  EXPECT_DOUBLE_EQ(s.geometry.mitral_diameter_mm, 24);
  EXPECT_DOUBLE_EQ(s.geometry.aortic_diameter_mm, 19);
  EXPECT_DOUBLE_EQ(s.geometry.lv_volume_ml, 125);
  EXPECT_DOUBLE_EQ(s.electro.sigma_e_fibre_ms_per_cm, 25.0);
  EXPECT_DOUBLE_EQ(s.electro.sigma_i_cross_ms_per_cm, 0.8);
  EXPECT_DOUBLE_EQ(s.electro.surface_to_volume_per_cm, 1400);
  EXPECT_EQ(s.electro.lv_cell_model, "ttp06");
  EXPECT_EQ(s.electro.la_cell_model, "fhn_atrial");
  EXPECT_DOUBLE_EQ(s.fluid.kinematic_viscosity_m2_per_s, 4.8e-6);
  EXPECT_EQ(s.fluid.nx, 129);
  EXPECT_EQ(s.fluid.nz, 145);
  EXPECT_DOUBLE_EQ(s.fluid.darcy_permeability, 0.001);
  EXPECT_DOUBLE_EQ(s.period_ms(), 60000.0 / 70.0);
  // An empty document is the default scenario.
  EXPECT_EQ(to_json(parse_scenario(nlohmann::json::object())), to_json(s));
}

TEST(Config, EveryDefaultIsInsideItsOwnRange) {
  for (const Param& p : parameter_table()) {
    if (p.kind == Kind::kReal || p.kind == Kind::kInt) {
      EXPECT_TRUE(p.min_exclusive ? p.default_number > p.min : p.default_number >= p.min) << p.path;
      EXPECT_TRUE(p.max_exclusive ? p.default_number < p.max : p.default_number <= p.max) << p.path;
    }
    if (p.kind == Kind::kChoice) {
      bool found = false;
      for (auto c : p.choices) found = found || c == p.default_choice;
      EXPECT_TRUE(found) << p.path;
    }
  }
}

TEST(Config, OutOfRangeNamesFieldValueAndRange) {
  EXPECT_EQ(error_of({{"heart_rate_bpm", 400}}), "invalid scenario: heart_rate_bpm = 400 is out of range [20, 240]");
  EXPECT_NE(error_of({{"tissue", {{"lv", {{"fung_c_pa", 0}}}}}}).find("tissue.lv.fung_c_pa = 0 is out of range (0, 100000]"),
            std::string::npos);
  EXPECT_NE(error_of({{"beats", 2.5}}).find("beats = 2.5 is not an integer"), std::string::npos);
  EXPECT_NE(error_of({{"heart_rate_bpm", "fast"}}).find("heart_rate_bpm = \"fast\" is not a number"), std::string::npos);
}

TEST(Config, UnknownFieldsAndChoicesAreRejectedWithTheKnownOnes) {
  const std::string unknown = error_of({{"heart_rate_bmp", 70}});
  EXPECT_NE(unknown.find("unknown field 'heart_rate_bmp'"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("heart_rate_bpm"), std::string::npos) << unknown;
  const std::string nested = error_of({{"lumped", {{"lv", {{"emax", 2}}}}}});
  EXPECT_NE(nested.find("unknown field 'lumped.lv.emax'; did you mean 'emax_mmhg_per_ml'? known fields of lumped.lv: "
                        "contraction_ms, emax_mmhg_per_ml"),
            std::string::npos)
      << nested;
  const std::string model = error_of({{"electro", {{"lv_cell_model", "TTP6"}}}});
  EXPECT_NE(model.find("unknown electro.lv_cell_model 'TTP6'; known: ttp06, fhn, aliev_panfilov, mitchell_schaeffer"),
            std::string::npos)
      << model;
}

TEST(Config, AllProblemsAreReportedAtOnce) {
  const std::string all = error_of({{"heart_rate_bpm", 1000}, {"beats", 0}, {"av_delay_ms", -5}});
  EXPECT_NE(all.find("3 problems"), std::string::npos) << all;
  EXPECT_NE(all.find("heart_rate_bpm = 1000"), std::string::npos);
  EXPECT_NE(all.find("beats = 0"), std::string::npos);
  EXPECT_NE(all.find("av_delay_ms = -5"), std::string::npos);
}

TEST(Config, CrossFieldRules) {
  EXPECT_NE(error_of({{"heart_rate_bpm", 200}, {"av_delay_ms", 350}}).find("must be shorter than the cardiac period"),
            std::string::npos);
  EXPECT_NE(error_of({{"lumped", {{"lv", {{"emax_mmhg_per_ml", 0.05}}}}}})
                .find("lumped.lv.emax_mmhg_per_ml = 0.05 must exceed lumped.lv.emin_mmhg_per_ml"),
            std::string::npos);
  EXPECT_NE(error_of({{"geometry", {{"mitral_diameter_mm", 45}, {"lv_short_axis_mm", 40}}}})
                .find("geometry.mitral_diameter_mm = 45 must be smaller than geometry.lv_short_axis_mm = 40"),
            std::string::npos);
  EXPECT_NE(error_of({{"outputs", {{"field_phases", {0.5}}}}}).find("outputs.fields is empty"), std::string::npos);
  EXPECT_NE(error_of({{"outputs", {{"fields", {"pressure"}}, {"field_phases", {1.0}}}}}).find("[0, 1)"),
            std::string::npos);
}

TEST(Config, UnimplementedSceneIsAnErrorNotAFallback) {
  const std::string e = error_of({{"scene", "geometry"}});
  EXPECT_NE(e.find("scene 'geometry' is not implemented yet; implemented: lumped, analytic, fluid, electro, mechanics, "
                   "ibm, electromechanics, fsi, fsei"),
            std::string::npos)
      << e;
  EXPECT_NE(error_of({{"scene", "warp"}}).find("unknown scene 'warp'; known: lumped"), std::string::npos);
}

TEST(Config, OverridesTypeTheValueByTheTable) {
  nlohmann::json doc = nlohmann::json::object();
  apply_override(doc, "heart_rate_bpm=90");
  apply_override(doc, "beats=12");
  apply_override(doc, "lumped.lv.emin_mmhg_per_ml=0.1");
  apply_override(doc, "outputs.time_series=false");
  apply_override(doc, "coupling.mode=strong");
  apply_override(doc, "outputs.fields=pressure,velocity");
  apply_override(doc, "outputs.field_phases=0.1,0.5");
  const Scenario s = parse_scenario(doc);
  EXPECT_DOUBLE_EQ(s.heart_rate_bpm, 90);
  EXPECT_EQ(s.beats, 12);
  EXPECT_DOUBLE_EQ(s.lumped.lv.emin_mmhg_per_ml, 0.1);
  EXPECT_FALSE(s.outputs.time_series);
  EXPECT_EQ(s.coupling.mode, "strong");
  EXPECT_EQ(s.outputs.fields, (std::vector<std::string>{"pressure", "velocity"}));
  EXPECT_EQ(s.outputs.field_phases, (std::vector<double>{0.1, 0.5}));
  EXPECT_THROW(apply_override(doc, "heart_rate=90"), InputError);
  EXPECT_THROW(apply_override(doc, "no_equals_sign"), InputError);
  nlohmann::json bad = nlohmann::json::object();
  apply_override(bad, "heart_rate_bpm=fast");
  EXPECT_NE(error_of(bad).find("heart_rate_bpm = \"fast\" is not a number"), std::string::npos);
}

TEST(Config, ToJsonRoundTrips) {
  Scenario s = default_scenario();
  s.heart_rate_bpm = 82;
  s.outputs.fields = {"wss"};
  s.outputs.field_phases = {0.25};
  EXPECT_EQ(to_json(parse_scenario(to_json(s))), to_json(s));
}

// Scenes fsi/fsei take the calibrated layer for what the document leaves out; the document's
// own fields, fsei.defaults = seed and every other scene keep the table's defaults.
TEST(Config, FsiAndFseiTakeTheCalibratedDefaultsUnlessTheScenarioSetsTheField) {
  const nlohmann::json table = to_json(default_scenario());
  ASSERT_FALSE(fsei_calibrated_defaults().empty());
  for (const char* scene : {"fsi", "fsei"}) {
    const nlohmann::json got = to_json(parse_scenario({{"scene", scene}}));
    for (const SceneDefault& d : fsei_calibrated_defaults()) {
      nlohmann::json expected = nlohmann::json::object();
      apply_override(expected, std::string(d.path) + "=" + std::string(d.value));
      std::string pointer = "/" + std::string(d.path);
      for (char& c : pointer)
        if (c == '.') c = '/';
      const nlohmann::json::json_pointer ptr(pointer);
      EXPECT_NE(expected[ptr], table[ptr]) << d.path << ": the layer repeats the table's default";
      if (d.scene.empty() || d.scene == scene)
        EXPECT_EQ(got[ptr], expected[ptr]) << scene << " " << d.path;
      else  // another scene's entry: this scene keeps the table's default
        EXPECT_EQ(got[ptr], table[ptr]) << scene << " " << d.path;
    }
    EXPECT_EQ(got["fsei"]["defaults"], "calibrated");
  }
  // A field the scenario sets wins over the layer, at its table default too.
  const Scenario own = parse_scenario({{"scene", "fsi"}, {"tissue", {{"density_g_per_ml", 1.05}}},
                                       {"fsei", {{"forcing", {{"kernel", "mls"}}}}}});
  EXPECT_EQ(own.tissue.density_g_per_ml, 1.05);
  EXPECT_EQ(own.fsei.forcing.kernel, "mls");
  EXPECT_EQ(own.fsei.prescribed_peak_tension_kpa, 120.0);  // the rest stays calibrated
  // fsei.defaults = seed and the other scenes: the table's defaults.
  nlohmann::json seed = to_json(parse_scenario({{"scene", "fsi"}, {"fsei", {{"defaults", "seed"}}}}));
  seed["scene"] = table["scene"];
  seed["fsei"]["defaults"] = table["fsei"]["defaults"];
  EXPECT_EQ(seed, table);
  nlohmann::json em = to_json(parse_scenario({{"scene", "electromechanics"}}));
  em["scene"] = table["scene"];
  EXPECT_EQ(em, table);
  EXPECT_NE(error_of({{"scene", "fsi"}, {"fsei", {{"defaults", "tight"}}}}).find("fsei.defaults"), std::string::npos);
}

TEST(Config, ParameterMarkdownListsEveryField) {
  const std::string md = parameters_markdown();
  for (const Param& p : parameter_table()) EXPECT_NE(md.find("`" + std::string(p.path) + "`"), std::string::npos) << p.path;
}

// Every leaf of systole.v1.Scenario is a row of the table and vice versa, with matching types.
void collect_proto_paths(const google::protobuf::Descriptor* d, const std::string& prefix,
                         std::map<std::string, const google::protobuf::FieldDescriptor*>& out) {
  for (int i = 0; i < d->field_count(); ++i) {
    const auto* f = d->field(i);
    const std::string path = prefix.empty() ? f->name() : prefix + "." + f->name();
    if (f->type() == google::protobuf::FieldDescriptor::TYPE_MESSAGE)
      collect_proto_paths(f->message_type(), path, out);
    else
      out[path] = f;
  }
}

TEST(Config, ProtoAndParameterTableAgree) {
  std::map<std::string, const google::protobuf::FieldDescriptor*> proto;
  collect_proto_paths(v1::Scenario::descriptor(), "", proto);
  std::set<std::string> table;
  for (const Param& p : parameter_table()) table.insert(std::string(p.path));
  for (const auto& [path, field] : proto) {
    const Param* p = find_parameter(path);
    ASSERT_NE(p, nullptr) << "proto field " << path << " has no row in parameter_table.cc";
    using FD = google::protobuf::FieldDescriptor;
    switch (p->kind) {
      case Kind::kReal: EXPECT_EQ(field->cpp_type(), FD::CPPTYPE_DOUBLE) << path; break;
      case Kind::kInt: EXPECT_EQ(field->cpp_type(), FD::CPPTYPE_INT32) << path; break;
      case Kind::kBool: EXPECT_EQ(field->cpp_type(), FD::CPPTYPE_BOOL) << path; break;
      case Kind::kChoice:
      case Kind::kString: EXPECT_EQ(field->cpp_type(), FD::CPPTYPE_STRING) << path; break;
      case Kind::kRealList: EXPECT_TRUE(field->is_repeated() && field->cpp_type() == FD::CPPTYPE_DOUBLE) << path; break;
      case Kind::kChoiceList: EXPECT_TRUE(field->is_repeated() && field->cpp_type() == FD::CPPTYPE_STRING) << path; break;
    }
    if (!field->is_repeated()) {
      EXPECT_TRUE(field->has_presence()) << path << " must be `optional` so defaults apply";
    }
  }
  for (const auto& path : table) EXPECT_TRUE(proto.count(path)) << "table row " << path << " is not in scenario.proto";
}

TEST(Bridge, ProtoJsonPathRejectsUnknownFieldsAndAcceptsCamelCase) {
  EXPECT_THROW(bridge::scenario_proto_from_json_text(R"({"heart_rate": 70})"), InputError);
  EXPECT_THROW(bridge::scenario_proto_from_json_text(R"({"heart_rate_bpm": 70,)"), InputError);
  const auto camel = bridge::scenario_proto_from_json_text(R"({"heartRateBpm": 88, "lumped": {"lv": {"v0Ml": 12}}})");
  const Scenario s = bridge::validate(camel);
  EXPECT_DOUBLE_EQ(s.heart_rate_bpm, 88);
  EXPECT_DOUBLE_EQ(s.lumped.lv.v0_ml, 12);
  EXPECT_THROW(bridge::load_scenario_file("/nonexistent/scenario.json", {}), InputError);
}

}  // namespace
}  // namespace systole::config

namespace systole::config {
namespace {
// docs/parameters.md is generated from the table; this fails when someone changes the table
// and forgets `build/bin/systole-solve --list-parameters > docs/parameters.md`.
TEST(Config, ParameterReferenceInDocsIsCurrent) {
  std::ifstream in(std::string(SYSTOLE_SOURCE_DIR) + "/docs/parameters.md");
  ASSERT_TRUE(in) << "docs/parameters.md is missing";
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), parameters_markdown())
      << "regenerate: build/bin/systole-solve --list-parameters > docs/parameters.md";
}
// Every scenario in examples/ parses (the README and docs point users at them; campaign files,
// with a "base_scenario", are the campaign tests' business), and the full heart's example is the
// setting of the first whole beat in blood (docs/fsei.md, sessions 17-18: its checkpoint's
// fingerprint matched this file's scenario).
TEST(Config, EveryExampleScenarioParses) {
  int parsed = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(SYSTOLE_SOURCE_DIR) + "/examples")) {
    if (entry.path().extension() != ".json") continue;
    std::ifstream in(entry.path());
    const nlohmann::json doc = nlohmann::json::parse(in);
    if (doc.contains("base_scenario")) continue;
    EXPECT_NO_THROW(parse_scenario(doc)) << entry.path();
    ++parsed;
  }
  EXPECT_GE(parsed, 10);
  std::ifstream in(std::string(SYSTOLE_SOURCE_DIR) + "/examples/fsi_tight_beat.json");
  const Scenario s = parse_scenario(nlohmann::json::parse(in));
  EXPECT_EQ(s.scene, "fsi");
  EXPECT_EQ(s.fsei.forcing.kernel, "divergence_free");
  EXPECT_EQ(s.fluid.nz, 83);
}

}  // namespace
}  // namespace systole::config
