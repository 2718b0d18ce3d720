#include "solver/io/result_writer.h"

#include <hdf5.h>

#include <cmath>
#include <fstream>
#include <iomanip>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "solver/core/version.h"

namespace systole::io {
namespace fs = std::filesystem;

namespace {

// RAII for HDF5 identifiers: every handle is closed on every path.
class H5Handle {
 public:
  H5Handle(hid_t id, herr_t (*close)(hid_t), const std::string& what) : id_(id), close_(close) {
    if (id < 0) throw std::runtime_error("HDF5: cannot " + what);
  }
  ~H5Handle() {
    if (id_ >= 0) close_(id_);
  }
  H5Handle(const H5Handle&) = delete;
  H5Handle& operator=(const H5Handle&) = delete;
  operator hid_t() const { return id_; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

void check(herr_t status, const std::string& what) {
  if (status < 0) throw std::runtime_error("HDF5: cannot " + what);
}

void write_string_attribute(hid_t object, const std::string& name, const std::string& value) {
  H5Handle type(H5Tcopy(H5T_C_S1), H5Tclose, "copy string type");
  check(H5Tset_size(type, std::max<size_t>(value.size(), 1)), "size string type");
  check(H5Tset_strpad(type, H5T_STR_NULLPAD), "pad string type");
  H5Handle space(H5Screate(H5S_SCALAR), H5Sclose, "create scalar space");
  H5Handle attr(H5Acreate2(object, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
                "create attribute " + name);
  check(H5Awrite(attr, type, value.empty() ? "" : value.data()), "write attribute " + name);
}

std::string read_string_attribute(hid_t object, const std::string& name) {
  H5Handle attr(H5Aopen(object, name.c_str(), H5P_DEFAULT), H5Aclose, "open attribute " + name);
  H5Handle type(H5Aget_type(attr), H5Tclose, "type of " + name);
  const size_t size = H5Tget_size(type);
  std::string value(size, '\0');
  check(H5Aread(attr, type, value.data()), "read attribute " + name);
  while (!value.empty() && value.back() == '\0') value.pop_back();
  return value;
}

void write_double_attribute(hid_t object, const std::string& name, double value) {
  H5Handle space(H5Screate(H5S_SCALAR), H5Sclose, "create scalar space");
  H5Handle attr(H5Acreate2(object, name.c_str(), H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT),
                H5Aclose, "create attribute " + name);
  check(H5Awrite(attr, H5T_NATIVE_DOUBLE, &value), "write attribute " + name);
}

// A 1-D double dataset, chunked with shuffle + gzip (level 4), with a "unit" attribute.
void write_vector(hid_t group, const std::string& name, const std::vector<double>& values,
                  const std::string& unit) {
  const hsize_t n = values.size();
  H5Handle space(H5Screate_simple(1, &n, nullptr), H5Sclose, "create dataspace " + name);
  H5Handle props(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "create dataset properties");
  if (n > 0) {
    const hsize_t chunk = std::min<hsize_t>(n, 4096);
    check(H5Pset_chunk(props, 1, &chunk), "chunk " + name);
    check(H5Pset_shuffle(props), "shuffle " + name);
    check(H5Pset_deflate(props, 4), "gzip " + name);
  }
  H5Handle set(H5Dcreate2(group, name.c_str(), H5T_IEEE_F64LE, space, H5P_DEFAULT, props,
                          H5P_DEFAULT),
               H5Dclose, "create dataset " + name);
  if (n > 0) check(H5Dwrite(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()),
                   "write dataset " + name);
  write_string_attribute(set, "unit", unit);
}

std::vector<double> read_vector(hid_t group, const std::string& name) {
  H5Handle set(H5Dopen2(group, name.c_str(), H5P_DEFAULT), H5Dclose, "open dataset " + name);
  H5Handle space(H5Dget_space(set), H5Sclose, "space of " + name);
  hsize_t n = 0;
  H5Sget_simple_extent_dims(space, &n, nullptr);
  std::vector<double> values(n);
  if (n > 0)
    check(H5Dread(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()),
          "read dataset " + name);
  return values;
}

std::vector<std::string> member_names(hid_t group) {
  std::vector<std::string> names;
  H5Literate(
      group, H5_INDEX_CRT_ORDER, H5_ITER_INC, nullptr,
      [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
        static_cast<std::vector<std::string>*>(data)->push_back(name);
        return 0;
      },
      &names);
  return names;
}

hid_t create_ordered_group(hid_t parent, const char* name) {
  H5Handle props(H5Pcreate(H5P_GROUP_CREATE), H5Pclose, "group properties");
  H5Pset_link_creation_order(props, H5P_CRT_ORDER_TRACKED | H5P_CRT_ORDER_INDEXED);
  return H5Gcreate2(parent, name, H5P_DEFAULT, props, H5P_DEFAULT);
}

// Writes through a temporary file and renames it into place.
template <class WriteFn>
void atomic_write(const fs::path& file, WriteFn&& write) {
  const fs::path tmp = file.string() + ".tmp";
  write(tmp);
  fs::rename(tmp, file);
}

}  // namespace

std::string unit_from_name(const std::string& name) {
  static const std::vector<std::pair<std::string, std::string>> suffixes{
      {"_mmhg_s_per_ml", "mmHg*s/ml"}, {"_percent", "%"}, {"_l_min", "l/min"},
      {"_ml_s", "ml/s"},              {"_mmhg", "mmHg"},  {"_ml", "ml"},
      {"_bpm", "1/min"},              {"_ms", "ms"},      {"_s", "s"},
      {"_phase", "t/T"},              {"_deg", "deg"}};
  for (const auto& [suffix, unit] : suffixes)
    if (name.size() > suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0)
      return unit;
  return "";
}

void write_result_h5(const fs::path& file, const RunResult& result, const Provenance& provenance) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // failures become exceptions with a message
  atomic_write(file, [&](const fs::path& tmp) {
    H5Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, "file access properties");
    H5Handle h5(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl), H5Fclose,
                "create " + tmp.string());
    write_string_attribute(h5, "systole_version", kVersion);
    write_string_attribute(h5, "git_revision", kGitRevision);
    write_string_attribute(h5, "job_id", provenance.job_id);
    write_string_attribute(h5, "scenario_json", provenance.scenario_json);
    {
      H5Handle group(create_ordered_group(h5, "time_series"), H5Gclose, "create /time_series");
      for (const Series& s : result.series) write_vector(group, s.name, s.values, s.unit);
    }
    {
      H5Handle group(create_ordered_group(h5, "beats"), H5Gclose, "create /beats");
      bool has_index = !result.beats.empty() && result.beats.back().count("beat") > 0;
      if (!has_index) {
        std::vector<double> index;
        for (size_t b = 0; b < result.beats.size(); ++b) index.push_back(static_cast<double>(b + 1));
        write_vector(group, "beat", index, "");
      }
      if (!result.beats.empty())
        for (const auto& [name, _] : result.beats.back()) {
          std::vector<double> values;
          for (const auto& beat : result.beats) {
            auto it = beat.find(name);
            values.push_back(it == beat.end() ? std::nan("") : it->second);
          }
          write_vector(group, name, values, unit_from_name(name));
        }
    }
    if (!result.phase_averaged.empty()) {
      H5Handle group(create_ordered_group(h5, "phase_averaged"), H5Gclose, "create /phase_averaged");
      for (const Series& s : result.phase_averaged) write_vector(group, s.name, s.values, s.unit);
    }
    {
      H5Handle group(create_ordered_group(h5, "metrics"), H5Gclose, "create /metrics");
      for (const auto& [name, value] : result.metrics) write_double_attribute(group, name, value);
    }
    H5Fflush(h5, H5F_SCOPE_GLOBAL);
  });
}

H5Contents read_result_h5(const fs::path& file) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  H5Contents out;
  H5Handle h5(H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose, "open " + file.string());
  out.version = read_string_attribute(h5, "systole_version");
  out.git_revision = read_string_attribute(h5, "git_revision");
  out.scenario_json = read_string_attribute(h5, "scenario_json");
  {
    H5Handle group(H5Gopen2(h5, "time_series", H5P_DEFAULT), H5Gclose, "open /time_series");
    for (const auto& name : member_names(group)) {
      H5Handle set(H5Dopen2(group, name.c_str(), H5P_DEFAULT), H5Dclose, "open " + name);
      out.series.push_back({name, read_string_attribute(set, "unit"), read_vector(group, name)});
    }
  }
  if (H5Lexists(h5, "phase_averaged", H5P_DEFAULT) > 0) {
    H5Handle group(H5Gopen2(h5, "phase_averaged", H5P_DEFAULT), H5Gclose, "open /phase_averaged");
    for (const auto& name : member_names(group)) {
      H5Handle set(H5Dopen2(group, name.c_str(), H5P_DEFAULT), H5Dclose, "open " + name);
      out.phase_averaged.push_back({name, read_string_attribute(set, "unit"), read_vector(group, name)});
    }
  }
  {
    H5Handle group(H5Gopen2(h5, "beats", H5P_DEFAULT), H5Gclose, "open /beats");
    for (const auto& name : member_names(group)) out.beats[name] = read_vector(group, name);
  }
  {
    H5Handle group(H5Gopen2(h5, "metrics", H5P_DEFAULT), H5Gclose, "open /metrics");
    const int n = H5Aget_num_attrs(group);
    for (int i = 0; i < n; ++i) {
      H5Handle attr(H5Aopen_by_idx(group, ".", H5_INDEX_NAME, H5_ITER_INC, i, H5P_DEFAULT,
                                   H5P_DEFAULT),
                    H5Aclose, "open metric");
      char name[256];
      H5Aget_name(attr, sizeof name, name);
      double value = 0;
      check(H5Aread(attr, H5T_NATIVE_DOUBLE, &value), "read metric");
      out.metrics[name] = value;
    }
  }
  return out;
}

void write_metrics_json(const fs::path& file, const RunResult& result) {
  atomic_write(file, [&](const fs::path& tmp) {
    nlohmann::json doc = nlohmann::json::object();
    for (const auto& [name, value] : result.metrics) doc[name] = value;
    std::ofstream out(tmp);
    out << std::setw(2) << doc << "\n";
    if (!out) throw std::runtime_error("cannot write " + tmp.string());
  });
}

namespace {
const Series* find_series(const RunResult& result, const std::string& name) {
  for (const Series& s : result.series)
    if (s.name == name) return &s;
  return nullptr;
}
}  // namespace

bool has_pv_loop(const RunResult& result) {
  const Series* time = find_series(result, "time_s");
  const Series* volume = find_series(result, "lv_volume_ml");
  const Series* pressure = find_series(result, "lv_pressure_mmhg");
  return time && volume && pressure && volume->values.size() == time->values.size() &&
         pressure->values.size() == time->values.size();
}

void write_pv_loop_csv(const fs::path& file, const RunResult& result) {
  if (!has_pv_loop(result)) throw std::logic_error("write_pv_loop_csv: the result has no LV pressure and volume series");
  const Series& time = *find_series(result, "time_s");
  const Series& volume = *find_series(result, "lv_volume_ml");
  const Series& pressure = *find_series(result, "lv_pressure_mmhg");
  atomic_write(file, [&](const fs::path& tmp) {
    std::ofstream out(tmp);
    out << "time_s,lv_volume_ml,lv_pressure_mmhg\n" << std::setprecision(10);
    for (size_t i = 0; i < time.values.size(); ++i)
      out << time.values[i] << ',' << volume.values[i] << ',' << pressure.values[i] << '\n';
    if (!out) throw std::runtime_error("cannot write " + tmp.string());
  });
}

namespace {
// The series of equal length to the first as the columns of a CSV file (header = their names).
void write_columns_csv(const fs::path& file, const std::vector<Series>& series) {
  const size_t rows = series.front().values.size();
  std::vector<const Series*> columns;
  for (const Series& s : series)
    if (s.values.size() == rows) columns.push_back(&s);
  atomic_write(file, [&](const fs::path& tmp) {
    std::ofstream out(tmp);
    for (size_t c = 0; c < columns.size(); ++c) out << (c ? "," : "") << columns[c]->name;
    out << '\n' << std::setprecision(10);
    for (size_t i = 0; i < rows; ++i) {
      for (size_t c = 0; c < columns.size(); ++c) out << (c ? "," : "") << columns[c]->values[i];
      out << '\n';
    }
    if (!out) throw std::runtime_error("cannot write " + tmp.string());
  });
}
}  // namespace

void write_time_series_csv(const fs::path& file, const RunResult& result) {
  if (result.series.empty()) throw std::logic_error("write_time_series_csv: the result has no series");
  write_columns_csv(file, result.series);
}

std::vector<fs::path> write_results(const fs::path& dir, const RunResult& result,
                                    const Provenance& provenance) {
  fs::create_directories(dir);
  std::vector<fs::path> files{dir / "result.h5", dir / "metrics.json"};
  write_result_h5(files[0], result, provenance);
  write_metrics_json(files[1], result);
  if (!result.series.empty()) {
    files.push_back(dir / "time_series.csv");
    write_time_series_csv(files.back(), result);
  }
  if (!result.phase_averaged.empty()) {
    files.push_back(dir / "phase_averaged.csv");
    write_columns_csv(files.back(), result.phase_averaged);
  }
  if (has_pv_loop(result)) {
    files.push_back(dir / "pv_loop.csv");
    write_pv_loop_csv(files.back(), result);
  }
  return files;
}

}  // namespace systole::io
