// `systole campaign ...` (see campaign_cli.h): submit, watch, status, results, retry, cancel
// and list UQ campaigns through systole.v1.Campaigns.
#include "client/campaign_cli.h"
#include "client/rpc.h"

#include <hdf5.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <google/protobuf/util/json_util.h>
#include <grpcpp/grpcpp.h>
#include <nlohmann/json.hpp>

#include "proto/bridge/json_fields.h"
#include "proto/bridge/scenario_bridge.h"
#include "solver/config/parameter_table.h"
#include "solver/config/scenario.h"
#include "solver/core/errors.h"
#include "solver/core/nearest_names.h"
#include "solver/io/result_writer.h"
#include "systole/v1/campaign.grpc.pb.h"

namespace systole::cli {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

using client::CliError;

class CampaignClient {
 public:
  explicit CampaignClient(std::string address) : address_(std::move(address)) {
    grpc::ChannelArguments args;
    args.SetMaxReceiveMessageSize(512 << 20);  // GetCampaignSamples of a large campaign
    stub_ = v1::Campaigns::NewStub(grpc::CreateCustomChannel(address_, grpc::InsecureChannelCredentials(), args));
  }
  v1::Campaigns::Stub& stub() { return *stub_; }
  static std::unique_ptr<grpc::ClientContext> context(int timeout_s) { return client::make_context(timeout_s); }
  void check(const grpc::Status& status) const { client::check_status(status, address_); }

  v1::GetCampaignResponse get(const std::string& id) {
    v1::GetCampaignRequest request;
    request.set_id(id);
    v1::GetCampaignResponse response;
    auto ctx = context(120);
    check(stub().GetCampaign(ctx.get(), request, &response));
    return response;
  }

 private:

  std::string address_;
  std::unique_ptr<v1::Campaigns::Stub> stub_;
};

// ---- formatting ---------------------------------------------------------------------------

std::string to_json(const google::protobuf::Message& m, bool pretty) {
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  options.always_print_primitive_fields = true;  // zeros too: readers need not guess defaults
  options.add_whitespace = pretty;
  std::string text;
  const auto status = google::protobuf::util::MessageToJsonString(m, &text, options);
  if (!status.ok()) throw CliError("cannot print " + m.GetTypeName() + " as JSON: " + std::string(status.message()), 1);
  return text;
}

// Shortest text that reads back as the same double ("" for NaN: an empty CSV cell).
std::string exact(double v) {
  if (std::isnan(v)) return "";
  char buffer[32];
  const auto r = std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, r.ptr);
}

std::string sig(double v, int digits = 4) {
  if (std::isnan(v)) return "-";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.*g", digits, v);
  return buffer;
}

std::string fixed(double v, int decimals = 3) {
  if (std::isnan(v)) return "-";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, v);
  return buffer;
}

using client::format_time;

std::string one_line(std::string s) {
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  return s;
}

v1::Design effective_design(const v1::CampaignSpec& spec) {
  return spec.design() == v1::DESIGN_UNSPECIFIED ? v1::LATIN_HYPERCUBE : spec.design();
}

std::string describe(const v1::UncertainParameter& p) {
  std::ostringstream out;
  switch (p.distribution_case()) {
    case v1::UncertainParameter::kUniform: out << "uniform(" << p.uniform().min() << ", " << p.uniform().max() << ")"; break;
    case v1::UncertainParameter::kNormal: out << "normal(" << p.normal().mean() << ", " << p.normal().std() << ")"; break;
    case v1::UncertainParameter::kLognormal:
      out << "lognormal(log_mean " << p.lognormal().log_mean() << ", log_std " << p.lognormal().log_std() << ")";
      break;
    case v1::UncertainParameter::kTruncatedNormal:
      out << "truncated_normal(" << p.truncated_normal().mean() << ", " << p.truncated_normal().std() << ", ["
          << p.truncated_normal().min() << ", " << p.truncated_normal().max() << "])";
      break;
    case v1::UncertainParameter::DISTRIBUTION_NOT_SET: out << "(no distribution)"; break;
  }
  return out.str();
}

std::string parameter_unit(const std::string& path) {
  const config::Param* p = config::find_parameter(path);
  return p == nullptr ? "" : std::string(p->unit);
}

int count(const v1::Campaign& c, const char* state) {
  const auto it = c.jobs_by_state().find(state);
  return it == c.jobs_by_state().end() ? 0 : it->second;
}

int done(const v1::Campaign& c) { return count(c, "SUCCEEDED") + count(c, "FAILED") + count(c, "CANCELLED"); }

std::string state_counts(const v1::Campaign& c) {
  std::ostringstream out;
  bool first = true;
  for (const char* s : {"QUEUED", "RUNNING", "SUCCEEDED", "FAILED", "CANCELLED"}) {
    out << (first ? "" : "  ") << s << " " << count(c, s);
    first = false;
  }
  out << "  cached " << c.jobs_cached();
  return out.str();
}

std::string campaign_state(const v1::Campaign& c) {
  if (c.cancelled()) return c.finished() ? "CANCELLED" : "CANCELLING";
  return c.finished() ? "FINISHED" : "RUNNING";
}

void print_header(const v1::Campaign& c) {
  const auto& spec = c.spec();
  std::cout << "campaign    " << c.id() << (c.request_id().empty() ? "" : "  (request id " + c.request_id() + ")") << "\n"
            << "state       " << campaign_state(c) << "\n"
            << "scene       " << (spec.base_scenario().has_scene() ? spec.base_scenario().scene() : "(default)") << "\n"
            << "design      " << v1::Design_Name(effective_design(spec)) << ", " << spec.samples() << " base samples, "
            << c.jobs_total() << " jobs, seed " << spec.seed() << "\n"
            << "created     " << format_time(c.created_ms()) << "\n"
            << "parameters  ";
  for (int i = 0; i < spec.parameters_size(); ++i)
    std::cout << (i ? "            " : "") << spec.parameters(i).path() << " ~ " << describe(spec.parameters(i)) << "\n";
  if (spec.parameters_size() == 0) std::cout << "-\n";
  std::cout << "progress    " << done(c) << "/" << c.jobs_total() << " done  " << state_counts(c) << "\n";
}

// The summary table: one row per QoI, then per QoI one row per parameter.
void print_statistics(const v1::CampaignStatistics& s) {
  std::cout << "\nstatistics over " << s.samples_total() << " samples: " << s.samples_succeeded() << " succeeded, "
            << s.samples_failed() << " failed or cancelled" << (s.samples_failed() ? " (excluded)" : "") << "\n";
  if (s.qoi_size() == 0) return;
  size_t name_width = 20;
  for (const auto& q : s.qoi()) name_width = std::max(name_width, q.name().size() + 2);
  std::cout << std::left << std::setw(static_cast<int>(name_width)) << "quantity of interest" << std::setw(8) << "unit"
            << std::right << std::setw(7) << "n" << std::setw(12) << "mean" << std::setw(12) << "std" << std::setw(12)
            << "p5" << std::setw(12) << "p50" << std::setw(12) << "p95" << "\n";
  for (const auto& q : s.qoi()) {
    const bool any = q.samples_used() > 0;
    auto value = [&](double v) { return any ? sig(v) : std::string("-"); };
    const std::string unit = io::unit_from_name(q.name());
    std::cout << std::left << std::setw(static_cast<int>(name_width)) << q.name() << std::setw(8)
              << (unit.empty() ? "-" : unit) << std::right << std::setw(7) << q.samples_used() << std::setw(12)
              << value(q.mean()) << std::setw(12) << value(q.std()) << std::setw(12) << value(q.percentiles().p5())
              << std::setw(12) << value(q.percentiles().p50()) << std::setw(12) << value(q.percentiles().p95()) << "\n";
  }
  for (const auto& q : s.qoi()) {
    if (q.sensitivities_size() == 0) continue;
    bool sobol = false;
    size_t path_width = 12;
    for (const auto& p : q.sensitivities()) {
      sobol = sobol || p.has_sobol_first() || p.has_sobol_total();
      path_width = std::max(path_width, p.path().size() + 2);
    }
    std::cout << "\n" << q.name() << ": sensitivity to each parameter";
    if (sobol)
      std::cout << " (Sobol' indices with " << fixed(100 * s.confidence_level(), 0) << " % bootstrap intervals, "
                << s.sobol_rows_used() << " complete Saltelli rows)";
    std::cout << "\n  " << std::left << std::setw(static_cast<int>(path_width)) << "parameter" << std::right
              << std::setw(9) << "pearson" << std::setw(10) << "spearman";
    if (sobol) std::cout << "   " << std::left << std::setw(26) << "first order S1 [low, high]" << "  total ST [low, high]";
    std::cout << "\n";
    for (const auto& p : q.sensitivities()) {
      std::cout << "  " << std::left << std::setw(static_cast<int>(path_width)) << p.path() << std::right << std::setw(9)
                << fixed(p.pearson()) << std::setw(10) << fixed(p.spearman());
      if (sobol) {
        auto interval = [](const v1::Interval& i) {
          return fixed(i.estimate()) + " [" + fixed(i.low()) + ", " + fixed(i.high()) + "]";
        };
        std::cout << "   " << std::left << std::setw(26) << (p.has_sobol_first() ? interval(p.sobol_first()) : "-")
                  << "  " << (p.has_sobol_total() ? interval(p.sobol_total()) : "-") << std::right;
      }
      std::cout << "\n";
    }
  }
}

void print_failed(const std::string& id, const v1::CampaignStatistics& s) {
  if (s.failed_size() == 0) return;
  constexpr int kShown = 50;
  std::cout << "\n" << s.failed_size() << " failed or cancelled sample" << (s.failed_size() == 1 ? "" : "s")
            << " (excluded from the statistics):\n  " << std::left << std::setw(7) << "index" << std::setw(22) << "job"
            << std::setw(11) << "state" << "error\n";
  for (int i = 0; i < std::min(kShown, s.failed_size()); ++i) {
    const auto& f = s.failed(i);
    std::cout << "  " << std::setw(7) << f.index() << std::setw(22) << f.job_id() << std::setw(11)
              << v1::JobState_Name(f.state()) << (f.error().empty() ? "-" : one_line(f.error())) << "\n";
  }
  std::cout << std::right;
  if (s.failed_size() > kShown)
    std::cout << "  ... and " << s.failed_size() - kShown << " more: systole campaign results " << id
              << " --out DIR lists every sample\n";
  std::cout << "  retry them with: systole campaign retry " << id << "\n";
}

void print_summary(const v1::GetCampaignResponse& r) {
  print_header(r.campaign());
  print_statistics(r.statistics());
  print_failed(r.campaign().id(), r.statistics());
}

// ---- submit -------------------------------------------------------------------------------

double parse_number(const std::string& key, const std::string& text) {
  double v = 0;
  const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
  if (r.ec != std::errc() || r.ptr != text.data() + text.size() || text.empty())
    throw CliError("--set " + key + "=" + text + ": '" + text + "' is not a number", 2);
  return v;
}

std::string camel_case(const std::string& snake) {
  std::string out;
  bool upper = false;
  for (char c : snake) {
    if (c == '_') {
      upper = true;
      continue;
    }
    out += upper ? static_cast<char>(std::toupper(static_cast<unsigned char>(c))) : c;
    upper = false;
  }
  return out;
}

// `--set` on the spec document: base.<scenario field>=v (typed and checked by the parameter
// table, as `systole submit --set`) or one of the spec's scalar fields.
void apply_set(json& doc, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw CliError("--set '" + assignment + "': expected key=value, e.g. base.heart_rate_bpm=75 or samples=200", 2);
  const std::string key = assignment.substr(0, eq);
  const std::string value = assignment.substr(eq + 1);
  for (const std::string prefix : {"base.", "base_scenario.", "baseScenario."}) {
    if (key.rfind(prefix, 0) != 0) continue;
    const std::string field = doc.contains("baseScenario") && !doc.contains("base_scenario") ? "baseScenario" : "base_scenario";
    json& base = doc[field];
    if (base.is_null()) base = json::object();
    if (!base.is_object()) throw CliError("--set " + key + ": the spec's " + field + " is not a JSON object", 2);
    config::apply_override(base, key.substr(prefix.size()) + "=" + value);  // InputError names the field
    return;
  }
  json v;
  if (key == "samples" || key == "priority" || key == "bootstrap_resamples") {
    const double n = parse_number(key, value);
    if (n != std::floor(n)) throw CliError("--set " + assignment + ": " + key + " must be an integer", 2);
    v = static_cast<long long>(n);
  } else if (key == "seed") {
    unsigned long long n = 0;
    const auto r = std::from_chars(value.data(), value.data() + value.size(), n);
    if (r.ec != std::errc() || r.ptr != value.data() + value.size() || value.empty())
      throw CliError("--set " + assignment + ": seed must be a non-negative integer", 2);
    v = n;
  } else if (key == "design") {
    std::string upper = value;
    for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    v1::Design d;
    if (!v1::Design_Parse(upper, &d))
      throw CliError("--set " + assignment + ": design must be MONTE_CARLO, LATIN_HYPERCUBE, SOBOL or SALTELLI", 2);
    v = upper;
  } else if (key == "no_cache") {
    if (value != "true" && value != "false") throw CliError("--set " + assignment + ": no_cache must be true or false", 2);
    v = value == "true";
  } else if (key == "quantities_of_interest") {
    v = json::array();
    std::istringstream in(value);
    std::string item;
    while (std::getline(in, item, ','))
      if (!item.empty()) v.push_back(item);
  } else {
    const std::vector<std::string> keys{"samples", "seed", "design", "priority", "bootstrap_resamples", "no_cache",
                                        "quantities_of_interest"};
    throw CliError("--set " + assignment + ": unknown key '" + key + "'; " + did_you_mean(key, keys) +
                       "use base.<scenario field> (e.g. base.heart_rate_bpm=75) or one of samples, seed, design, "
                       "priority, bootstrap_resamples, no_cache, quantities_of_interest (edit parameters in the file)",
                   2);
  }
  doc.erase(camel_case(key));
  doc[key] = v;
}

v1::CampaignSpec load_spec(const std::string& file, const std::vector<std::string>& sets) {
  std::ifstream in(file);
  if (!in || fs::is_directory(file)) throw CliError("cannot read campaign spec '" + file + "'", 2);
  std::stringstream buffer;
  buffer << in.rdbuf();
  json doc;
  try {
    doc = json::parse(buffer.str());
  } catch (const json::parse_error& e) {
    throw CliError("campaign spec '" + file + "' is not valid JSON: " + e.what(), 2);
  }
  if (!doc.is_object()) throw CliError("campaign spec '" + file + "' must hold a JSON object (a systole.v1.CampaignSpec)", 2);
  for (const auto& s : sets) apply_set(doc, s);
  v1::CampaignSpec spec;
  // Every unknown key (with the nearest allowed names), then the base scenario with the
  // server's own checks, in one error before anything is sent.
  bridge::JsonParse parse = bridge::parse_json_message(doc.dump(), spec);
  if (parse.parsed)
    for (const auto& p : bridge::scenario_problems(spec.base_scenario())) parse.problems.push_back("base_scenario: " + p);
  const auto& all = parse.problems;
  if (all.empty()) return spec;
  std::string text = "campaign spec '" + file + "'" + (all.size() == 1 ? ": " : " (" + std::to_string(all.size()) + " problems):\n  ");
  for (std::size_t i = 0; i < all.size(); ++i) text += (i ? "\n  " : "") + all[i];
  throw CliError(text, 2);
}

// ---- results files ------------------------------------------------------------------------

std::string csv_cell(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

// Writes via a temporary name and a rename: a reader never sees half a file.
template <class Write>
void atomic_write(const fs::path& file, Write write) {
  const fs::path tmp = file.string() + ".part";
  try {
    write(tmp);
    fs::rename(tmp, file);
  } catch (...) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw;
  }
}

struct Table {
  std::vector<v1::CampaignSample> rows;  // sorted by index
  std::vector<std::string> inputs;       // parameter paths, spec order
  std::vector<std::string> outputs;      // QoIs, spec order
  double input(size_t r, size_t c) const {
    const auto& m = rows[r].inputs();
    const auto it = m.find(inputs[c]);
    return it == m.end() ? std::nan("") : it->second;
  }
  double output(size_t r, size_t c) const {
    const auto& m = rows[r].outputs();
    const auto it = m.find(outputs[c]);
    return it == m.end() ? std::nan("") : it->second;
  }
};

void write_csv(const fs::path& file, const Table& t) {
  atomic_write(file, [&](const fs::path& tmp) {
    std::ofstream out(tmp);
    if (!out) throw CliError("cannot write " + tmp.string(), 1);
    out << "index,job_id,state";
    for (const auto& p : t.inputs) out << "," << csv_cell(p);
    for (const auto& q : t.outputs) out << "," << csv_cell(q);
    out << ",cached_from,error\n";
    for (size_t r = 0; r < t.rows.size(); ++r) {
      const auto& s = t.rows[r];
      out << s.index() << "," << csv_cell(s.job_id()) << "," << v1::JobState_Name(s.state());
      for (size_t c = 0; c < t.inputs.size(); ++c) out << "," << exact(t.input(r, c));
      for (size_t c = 0; c < t.outputs.size(); ++c) out << "," << exact(t.output(r, c));
      out << "," << csv_cell(s.cached_from()) << "," << csv_cell(s.error()) << "\n";
    }
    out.close();
    if (!out) throw CliError("cannot write " + tmp.string(), 1);
  });
}

// RAII for HDF5 identifiers.
class H5 {
 public:
  H5(hid_t id, herr_t (*close)(hid_t), const std::string& what) : id_(id), close_(close) {
    if (id < 0) throw CliError("HDF5: cannot " + what, 1);
  }
  ~H5() {
    if (id_ >= 0) close_(id_);
  }
  H5(const H5&) = delete;
  H5& operator=(const H5&) = delete;
  operator hid_t() const { return id_; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

void h5check(herr_t status, const std::string& what) {
  if (status < 0) throw CliError("HDF5: cannot " + what, 1);
}

hid_t vlen_string_type() {
  const hid_t t = H5Tcopy(H5T_C_S1);
  if (t >= 0) {
    H5Tset_size(t, H5T_VARIABLE);
    H5Tset_cset(t, H5T_CSET_UTF8);
  }
  return t;
}

void string_attribute(hid_t object, const std::string& name, const std::string& value) {
  H5 type(vlen_string_type(), H5Tclose, "make a string type");
  H5 space(H5Screate(H5S_SCALAR), H5Sclose, "create a scalar space");
  H5 attr(H5Acreate2(object, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose, "create attribute " + name);
  const char* p = value.c_str();
  h5check(H5Awrite(attr, type, &p), "write attribute " + name);
}

void strings_attribute(hid_t object, const std::string& name, const std::vector<std::string>& values) {
  H5 type(vlen_string_type(), H5Tclose, "make a string type");
  const hsize_t n = values.size();
  H5 space(H5Screate_simple(1, &n, nullptr), H5Sclose, "create a space for " + name);
  H5 attr(H5Acreate2(object, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose, "create attribute " + name);
  std::vector<const char*> p;
  for (const auto& v : values) p.push_back(v.c_str());
  if (n) h5check(H5Awrite(attr, type, p.data()), "write attribute " + name);
}

void number_attribute(hid_t object, const std::string& name, const std::vector<double>& values) {
  const hsize_t n = values.size();
  H5 space(values.size() == 1 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr), H5Sclose, "create a space");
  H5 attr(H5Acreate2(object, name.c_str(), H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
          "create attribute " + name);
  h5check(H5Awrite(attr, H5T_NATIVE_DOUBLE, values.data()), "write attribute " + name);
}

// A dataset of `dims` (rank 0 = scalar) from `data` in memory type `memory`.
hid_t dataset(hid_t group, const std::string& name, hid_t file_type, hid_t memory_type, std::vector<hsize_t> dims,
              const void* data) {
  const hid_t space = dims.empty() ? H5Screate(H5S_SCALAR)
                                   : H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr);
  H5 space_handle(space, H5Sclose, "create a space for " + name);
  const hid_t set = H5Dcreate2(group, name.c_str(), file_type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (set < 0) throw CliError("HDF5: cannot create dataset " + name, 1);
  hsize_t elements = 1;
  for (hsize_t d : dims) elements *= d;
  if (elements > 0 && H5Dwrite(set, memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
    H5Dclose(set);
    throw CliError("HDF5: cannot write dataset " + name, 1);
  }
  return set;
}

void doubles(hid_t group, const std::string& name, const std::vector<double>& v, const std::string& unit = "",
             std::vector<hsize_t> dims = {}) {
  if (dims.empty()) dims = {v.size()};
  H5 set(dataset(group, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, dims, v.data()), H5Dclose, "write " + name);
  if (!unit.empty()) string_attribute(set, "unit", unit);
}

void scalar(hid_t group, const std::string& name, double v, const std::string& unit = "") {
  H5 set(dataset(group, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {}, &v), H5Dclose, "write " + name);
  if (!unit.empty()) string_attribute(set, "unit", unit);
}

void ints(hid_t group, const std::string& name, const std::vector<int32_t>& v) {
  H5 set(dataset(group, name, H5T_STD_I32LE, H5T_NATIVE_INT32, {v.size()}, v.data()), H5Dclose, "write " + name);
}

void strings(hid_t group, const std::string& name, const std::vector<std::string>& v) {
  H5 type(vlen_string_type(), H5Tclose, "make a string type");
  std::vector<const char*> p;
  for (const auto& s : v) p.push_back(s.c_str());
  H5 set(dataset(group, name, type, type, {v.size()}, p.data()), H5Dclose, "write " + name);
}

hid_t group(hid_t parent, const std::string& name) {
  H5 props(H5Pcreate(H5P_GROUP_CREATE), H5Pclose, "create group properties");
  H5Pset_link_creation_order(props, H5P_CRT_ORDER_TRACKED | H5P_CRT_ORDER_INDEXED);
  return H5Gcreate2(parent, name.c_str(), H5P_DEFAULT, props, H5P_DEFAULT);
}

std::string group_name(std::string s) {
  std::replace(s.begin(), s.end(), '/', '_');
  return s.empty() ? "_" : s;
}

void write_h5(const fs::path& file, const v1::GetCampaignResponse& campaign, const Table& t) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // failures become exceptions with a message
  atomic_write(file, [&](const fs::path& tmp) {
    H5 fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, "create file access properties");
    h5check(H5Pset_libver_bounds(fapl, H5F_LIBVER_V18, H5F_LIBVER_LATEST), "set the file format");  // large attributes
    H5 h5(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl), H5Fclose, "create " + tmp.string());
    const auto& c = campaign.campaign();
    string_attribute(h5, "campaign_id", c.id());
    string_attribute(h5, "spec_json", to_json(c.spec(), false));
    string_attribute(h5, "design", v1::Design_Name(effective_design(c.spec())));
    string_attribute(h5, "state", campaign_state(c));
    number_attribute(h5, "jobs_total", {static_cast<double>(c.jobs_total())});
    number_attribute(h5, "jobs_cached", {static_cast<double>(c.jobs_cached())});

    const size_t n = t.rows.size(), d = t.inputs.size(), q = t.outputs.size();
    {
      H5 g(group(h5, "samples"), H5Gclose, "create /samples");
      std::vector<int32_t> index, state;
      std::vector<std::string> job, cached, error;
      for (const auto& s : t.rows) {
        index.push_back(s.index());
        state.push_back(static_cast<int32_t>(s.state()));
        job.push_back(s.job_id());
        cached.push_back(s.cached_from());
        error.push_back(s.error());
      }
      ints(g, "index", index);
      strings(g, "job_id", job);
      {
        H5 set(dataset(g, "state", H5T_STD_I32LE, H5T_NATIVE_INT32, {n}, state.data()), H5Dclose, "write state");
        std::vector<std::string> legend;
        for (int s = v1::JobState_MIN; s <= v1::JobState_MAX; ++s) legend.push_back(v1::JobState_Name(s));
        strings_attribute(set, "legend", legend);  // state value i is legend[i]
      }
      strings(g, "cached_from", cached);
      strings(g, "error", error);
      std::vector<double> in(n * d), out(n * q);
      for (size_t r = 0; r < n; ++r) {
        for (size_t k = 0; k < d; ++k) in[r * d + k] = t.input(r, k);
        for (size_t k = 0; k < q; ++k) out[r * q + k] = t.output(r, k);  // NaN: failed or not finished
      }
      {
        H5 set(dataset(g, "inputs", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {n, d}, in.data()), H5Dclose, "write inputs");
        std::vector<std::string> units;
        for (const auto& p : t.inputs) units.push_back(parameter_unit(p));
        strings_attribute(set, "paths", t.inputs);
        strings_attribute(set, "units", units);
      }
      {
        H5 set(dataset(g, "outputs", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {n, q}, out.data()), H5Dclose, "write outputs");
        std::vector<std::string> units;
        for (const auto& name : t.outputs) units.push_back(io::unit_from_name(name));
        strings_attribute(set, "names", t.outputs);
        strings_attribute(set, "units", units);
      }
    }
    {
      const auto& s = campaign.statistics();
      H5 g(group(h5, "statistics"), H5Gclose, "create /statistics");
      number_attribute(g, "samples_total", {static_cast<double>(s.samples_total())});
      number_attribute(g, "samples_succeeded", {static_cast<double>(s.samples_succeeded())});
      number_attribute(g, "samples_failed", {static_cast<double>(s.samples_failed())});
      number_attribute(g, "confidence_level", {s.confidence_level()});
      number_attribute(g, "sobol_rows_used", {static_cast<double>(s.sobol_rows_used())});
      for (const auto& qoi : s.qoi()) {
        H5 qg(group(g, group_name(qoi.name())), H5Gclose, "create /statistics/" + qoi.name());
        const std::string unit = io::unit_from_name(qoi.name());
        string_attribute(qg, "unit", unit);
        {
          const int32_t used = qoi.samples_used();
          H5 set(dataset(qg, "samples_used", H5T_STD_I32LE, H5T_NATIVE_INT32, {}, &used), H5Dclose, "write samples_used");
        }
        scalar(qg, "mean", qoi.mean(), unit);
        scalar(qg, "std", qoi.std(), unit);
        {
          const auto& p = qoi.percentiles();
          H5 set(dataset(qg, "percentiles", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {5},
                         std::vector<double>{p.p5(), p.p25(), p.p50(), p.p75(), p.p95()}.data()),
                 H5Dclose, "write percentiles");
          number_attribute(set, "levels_percent", {5, 25, 50, 75, 95});
          if (!unit.empty()) string_attribute(set, "unit", unit);
        }
        doubles(qg, "histogram_edges", {qoi.histogram().edges().begin(), qoi.histogram().edges().end()}, unit);
        ints(qg, "histogram_counts", {qoi.histogram().counts().begin(), qoi.histogram().counts().end()});
        std::vector<std::string> paths;
        std::vector<double> pearson, spearman;
        std::map<std::string, std::vector<double>> sobol;
        bool has_sobol = false;
        const double nan = std::nan("");
        for (const auto& p : qoi.sensitivities()) {
          paths.push_back(p.path());
          pearson.push_back(p.pearson());
          spearman.push_back(p.spearman());
          has_sobol = has_sobol || p.has_sobol_first() || p.has_sobol_total();
          sobol["sobol_first"].push_back(p.has_sobol_first() ? p.sobol_first().estimate() : nan);
          sobol["sobol_first_low"].push_back(p.has_sobol_first() ? p.sobol_first().low() : nan);
          sobol["sobol_first_high"].push_back(p.has_sobol_first() ? p.sobol_first().high() : nan);
          sobol["sobol_total"].push_back(p.has_sobol_total() ? p.sobol_total().estimate() : nan);
          sobol["sobol_total_low"].push_back(p.has_sobol_total() ? p.sobol_total().low() : nan);
          sobol["sobol_total_high"].push_back(p.has_sobol_total() ? p.sobol_total().high() : nan);
        }
        strings(qg, "parameters", paths);  // the order of pearson, spearman and sobol_*
        doubles(qg, "pearson", pearson);
        doubles(qg, "spearman", spearman);
        if (has_sobol)
          for (const char* name : {"sobol_first", "sobol_first_low", "sobol_first_high", "sobol_total",
                                   "sobol_total_low", "sobol_total_high"})
            doubles(qg, name, sobol[name]);
      }
    }
    h5check(H5Fflush(h5, H5F_SCOPE_GLOBAL), "flush " + tmp.string());
  });
}

void write_text(const fs::path& file, const std::string& text) {
  atomic_write(file, [&](const fs::path& tmp) {
    std::ofstream out(tmp);
    out << text << "\n";
    out.close();
    if (!out) throw CliError("cannot write " + tmp.string(), 1);
  });
}

// ---- the commands -------------------------------------------------------------------------

class Commands final : public CampaignCommands {
 public:
  explicit Commands(CLI::App& app) {
    group_ = app.add_subcommand("campaign", "UQ campaigns: submit | watch | status | results | retry | cancel | list");
    group_->require_subcommand(1);
    group_->fallthrough();  // --server after `campaign ...` too

    submit_ = sub("submit", "submit a campaign (a CampaignSpec in proto3 JSON, see examples/campaign-0d.json); prints its id");
    submit_->add_option("spec", file_, "campaign spec JSON file")->required();
    submit_->add_option("--set", sets_,
                        "override: base.<scenario field>=value, or samples|seed|design|priority|"
                        "bootstrap_resamples|no_cache|quantities_of_interest=value (repeatable)");
    submit_->add_option("--request-id", request_id_, "idempotency key: submitting again returns the same campaign");

    watch_ = sub("watch", "progress until the campaign finishes, then the summary; exit 1 if any sample failed");
    watch_->add_option("id", id_)->required();
    watch_->add_flag("--quiet", quiet_, "no progress output, only the summary");

    status_ = sub("status", "progress and statistics of the samples finished so far");
    status_->add_option("id", id_)->required();
    status_->add_flag("--json", json_, "the GetCampaignResponse as JSON");

    results_ = sub("results", "write DIR/campaign.csv, DIR/campaign.h5 and DIR/statistics.json");
    results_->add_option("id", id_)->required();
    results_->add_option("--out", out_, "directory (created if missing)")->required();

    retry_ = sub("retry", "put the failed and cancelled samples back in the queue");
    retry_->add_option("id", id_)->required();

    cancel_ = sub("cancel", "cancel every queued sample and stop the running ones");
    cancel_->add_option("id", id_)->required();

    list_ = sub("list", "list campaigns, newest first");
    list_->add_option("--page-size", page_size_, "campaigns per page")->capture_default_str();
    list_->add_option("--page-token", page_token_, "continue a listing");
  }

  bool selected() const override { return group_->parsed(); }

  int run(const std::string& server) override {
    try {
      CampaignClient client(server);
      if (submit_->parsed()) return submit(client);
      if (watch_->parsed()) return watch(client);
      if (status_->parsed()) return status(client);
      if (results_->parsed()) return results(client);
      if (retry_->parsed()) return retry(client);
      if (cancel_->parsed()) return cancel(client);
      if (list_->parsed()) return list(client);
      throw CliError("campaign: name a subcommand (submit, watch, status, results, retry, cancel, list)", 2);
    } catch (const CliError& e) {
      std::cerr << "systole: " << e.what() << "\n";
      return e.exit_code;
    } catch (const InputError& e) {
      std::cerr << "systole: " << e.what() << "\n";
      return 2;
    } catch (const std::exception& e) {
      std::cerr << "systole: " << e.what() << "\n";
      return 1;
    }
  }

 private:
  CLI::App* sub(const char* name, const char* help) {
    CLI::App* c = group_->add_subcommand(name, help);
    c->fallthrough();
    return c;
  }

  int submit(CampaignClient& client) {
    v1::SubmitCampaignRequest request;
    *request.mutable_spec() = load_spec(file_, sets_);
    request.set_request_id(request_id_);
    v1::SubmitCampaignResponse response;
    auto ctx = CampaignClient::context(120);  // inserts every job in one transaction
    client.check(client.stub().SubmitCampaign(ctx.get(), request, &response));
    const auto& c = response.campaign();
    std::cout << c.id() << std::endl;
    std::cerr << (response.created() ? "submitted " : "already submitted with request id " + request_id_ + ": ") << c.id()
              << ": " << c.jobs_total() << " jobs (" << v1::Design_Name(effective_design(c.spec())) << "), "
              << c.jobs_cached() << " served from the result cache\n";
    return 0;
  }

  int watch(CampaignClient& client) {
    const bool tty = !quiet_ && ::isatty(1);
    const auto start = std::chrono::steady_clock::now();
    std::string last;
    bool received = false, bar_shown = false;
    v1::GetCampaignResponse latest;
    for (int attempt = 0; attempt < 30; ++attempt) {
      auto ctx = CampaignClient::context(0);
      v1::WatchCampaignRequest request;
      request.set_id(id_);
      auto reader = client.stub().WatchCampaign(ctx.get(), request);
      v1::GetCampaignResponse response;
      while (reader->Read(&response)) {
        received = true;
        attempt = 0;
        latest = response;
        const auto& c = response.campaign();
        const std::string line = std::to_string(done(c)) + "/" + std::to_string(c.jobs_total()) + " done  " + state_counts(c);
        if (quiet_ || line == last) continue;
        last = line;
        if (tty) {
          constexpr int kWidth = 30;
          const double fraction = c.jobs_total() ? static_cast<double>(done(c)) / c.jobs_total() : 1.0;
          const int filled = static_cast<int>(std::clamp(fraction, 0.0, 1.0) * kWidth);
          std::cout << "\r\033[K[" << std::string(filled, '#') << std::string(kWidth - filled, '.') << "] " << line
                    << std::flush;
          bar_shown = true;
        } else {
          const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
          std::cout << "[" << fixed(elapsed, 1) << " s] " << line << std::endl;
        }
      }
      const grpc::Status status = reader->Finish();
      if (status.ok() && latest.campaign().finished()) break;
      const bool transient = status.ok() || status.error_code() == grpc::StatusCode::UNAVAILABLE ||
                             status.error_code() == grpc::StatusCode::CANCELLED;
      if (!transient || !received) client.check(status.ok() ? grpc::Status(grpc::StatusCode::UNAVAILABLE, "stream ended") : status);
      std::this_thread::sleep_for(std::chrono::seconds(1));  // server restarting: watch again
    }
    if (bar_shown) std::cout << "\n";
    if (!latest.campaign().finished()) throw CliError("lost the connection to the server while watching " + id_, 3);
    if (!latest.has_statistics()) latest = client.get(id_);
    std::cout << "\n";
    print_summary(latest);
    const auto& s = latest.statistics();
    return s.samples_failed() == 0 && s.samples_succeeded() == s.samples_total() ? 0 : 1;
  }

  int status(CampaignClient& client) {
    const auto response = client.get(id_);
    if (json_) {
      std::cout << to_json(response, true) << "\n";
      return 0;
    }
    print_summary(response);
    return 0;
  }

  int results(CampaignClient& client) {
    const auto campaign = client.get(id_);
    v1::GetCampaignSamplesRequest request;
    request.set_id(id_);
    v1::GetCampaignSamplesResponse samples;
    auto ctx = CampaignClient::context(300);
    client.check(client.stub().GetCampaignSamples(ctx.get(), request, &samples));

    Table t;
    t.rows.assign(samples.samples().begin(), samples.samples().end());
    std::sort(t.rows.begin(), t.rows.end(), [](const auto& a, const auto& b) { return a.index() < b.index(); });
    for (const auto& p : campaign.campaign().spec().parameters()) t.inputs.push_back(p.path());
    for (const auto& q : campaign.campaign().spec().quantities_of_interest()) t.outputs.push_back(q);

    const fs::path dir(out_);
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir)) throw CliError("cannot create directory '" + out_ + "': " + ec.message(), 1);
    write_csv(dir / "campaign.csv", t);
    write_h5(dir / "campaign.h5", campaign, t);
    write_text(dir / "statistics.json", to_json(campaign, true));
    const auto& c = campaign.campaign();
    if (!c.finished())
      std::cerr << "systole: campaign " << id_ << " is not finished (" << done(c) << "/" << c.jobs_total()
                << " done): the files hold what has finished so far\n";
    std::cout << "wrote " << fs::absolute(dir / "campaign.csv").string() << " (" << t.rows.size() << " samples)\n"
              << "wrote " << fs::absolute(dir / "campaign.h5").string() << "\n"
              << "wrote " << fs::absolute(dir / "statistics.json").string() << "\n";
    return 0;
  }

  int retry(CampaignClient& client) {
    const auto before = client.get(id_).campaign();
    const int n = count(before, "FAILED") + count(before, "CANCELLED");
    if (n == 0) {
      std::cout << id_ << ": no failed or cancelled samples to retry\n";
      return 0;
    }
    v1::RetryFailedRequest request;
    request.set_id(id_);
    v1::Campaign c;
    auto ctx = CampaignClient::context(60);
    client.check(client.stub().RetryFailed(ctx.get(), request, &c));
    std::cout << id_ << ": " << n << " failed or cancelled sample" << (n == 1 ? "" : "s") << " queued again\n"
              << "progress  " << done(c) << "/" << c.jobs_total() << " done  " << state_counts(c) << "\n"
              << "follow it with: systole campaign watch " << id_ << "\n";
    return 0;
  }

  int cancel(CampaignClient& client) {
    v1::CancelCampaignRequest request;
    request.set_id(id_);
    v1::Campaign c;
    auto ctx = CampaignClient::context(60);
    client.check(client.stub().CancelCampaign(ctx.get(), request, &c));
    std::cout << c.id() << " " << campaign_state(c) << "\n"
              << "progress  " << done(c) << "/" << c.jobs_total() << " done  " << state_counts(c) << "\n";
    if (count(c, "RUNNING") > 0) std::cout << "the running samples stop shortly\n";
    return 0;
  }

  int list(CampaignClient& client) {
    v1::ListCampaignsRequest request;
    request.set_page_size(page_size_);
    request.set_page_token(page_token_);
    v1::ListCampaignsResponse response;
    auto ctx = CampaignClient::context(60);
    client.check(client.stub().ListCampaigns(ctx.get(), request, &response));
    std::cout << std::left << std::setw(22) << "ID" << std::setw(11) << "STATE" << std::setw(16) << "DESIGN"
              << std::setw(9) << "SCENE" << std::right << std::setw(7) << "JOBS" << std::setw(7) << "DONE"
              << std::setw(7) << "FAILED" << std::setw(7) << "CACHED" << "  CREATED\n";
    for (const auto& c : response.campaigns())
      std::cout << std::left << std::setw(22) << c.id() << std::setw(11) << campaign_state(c) << std::setw(16)
                << v1::Design_Name(effective_design(c.spec())) << std::setw(9)
                << (c.spec().base_scenario().has_scene() ? c.spec().base_scenario().scene() : "-") << std::right
                << std::setw(7) << c.jobs_total() << std::setw(7) << done(c) << std::setw(7)
                << count(c, "FAILED") + count(c, "CANCELLED") << std::setw(7) << c.jobs_cached() << "  "
                << format_time(c.created_ms()) << "\n";
    if (!response.next_page_token().empty())
      std::cout << "more: systole campaign list --page-token " << response.next_page_token() << "\n";
    return 0;
  }

  CLI::App* group_ = nullptr;
  CLI::App *submit_ = nullptr, *watch_ = nullptr, *status_ = nullptr, *results_ = nullptr, *retry_ = nullptr,
           *cancel_ = nullptr, *list_ = nullptr;
  std::string file_, id_, request_id_, out_, page_token_;
  std::vector<std::string> sets_;
  int page_size_ = 50;
  bool quiet_ = false, json_ = false;
};

}  // namespace

std::unique_ptr<CampaignCommands> add_campaign_commands(CLI::App& app) { return std::make_unique<Commands>(app); }

}  // namespace systole::cli
