#include "solver/scene/fsei/checkpoint.h"

#include <hdf5.h>
#include <mpi.h>

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <vector>

#include "solver/config/parameter_table.h"
#include "solver/config/removed_fields.h"
#include "solver/core/errors.h"
#include "solver/scene/h5_dataset.h"

namespace systole::scene {
namespace {

namespace fs = std::filesystem;

std::string exact(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

// What a continued run may change (none of it is the model): the outputs, the run's length, the
// field and checkpoint intervals, the slow-runaway guard's bounds, the structure's strain limit (a guard that stops the run, not a parameter of the
// trajectory: the pre-stress does not depend on it either, prestress.h), so a run stopped by it
// resumes from its last checkpoint with a looser one, the slabs' split over the ranks (like
// the rank count: the trajectory to round-off), and the fluid's CFL target and rule (ours: the
// step's size, not the model: a run stopped by the fluid's CFL or energy guard resumes from its
// last checkpoint at a smaller CFL; the trajectory then differs by the time discretisation's
// error, docs/fsei.md).
bool excluded(std::string_view path) {
  return path.rfind("outputs.", 0) == 0 || path == "beats" || path == "fsei.end_time_ms" ||
         path == "fsei.field_interval_ms" || path == "fsei.checkpoint_interval_ms" ||
         path == "structure.strain_limit" || path == "fsei.slab_split" || path == "fluid.cfl" ||
         path == "fluid.cfl_rule" || path == "fsei.abort_mean_speed_m_s" ||
         path == "fsei.abort_mean_speed_orifice_ratio";
}

std::string entry_name(std::size_t k) { return std::string("e").append(std::to_string(k)); }

void barrier() {
  int ready = 0;
  MPI_Initialized(&ready);
  if (ready) MPI_Barrier(MPI_COMM_WORLD);
}

std::vector<double> read_doubles(hid_t file, const std::string& name, const fs::path& path) {
  const hid_t set = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
  if (set < 0) throw std::runtime_error(std::string("checkpoint ") + path.string() + ": no dataset " + name);
  const hid_t space = H5Dget_space(set);
  hsize_t n = 0;
  if (H5Sget_simple_extent_ndims(space) == 1) H5Sget_simple_extent_dims(space, &n, nullptr);
  std::vector<double> out(static_cast<std::size_t>(n));
  const bool ok = n == 0 || H5Dread(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) >= 0;
  H5Sclose(space);
  H5Dclose(set);
  if (!ok) throw std::runtime_error(std::string("checkpoint ") + path.string() + ": cannot read dataset " + name);
  return out;
}

std::string read_text(hid_t file, const std::string& name, const fs::path& path) {
  const hid_t set = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
  if (set < 0) throw std::runtime_error(std::string("checkpoint ") + path.string() + ": no dataset " + name);
  const hid_t space = H5Dget_space(set);
  hsize_t n = 0;
  if (H5Sget_simple_extent_ndims(space) == 1) H5Sget_simple_extent_dims(space, &n, nullptr);
  std::string out(static_cast<std::size_t>(n), '\0');
  const bool ok = n == 0 || H5Dread(set, H5T_NATIVE_CHAR, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) >= 0;
  H5Sclose(space);
  H5Dclose(set);
  if (!ok) throw std::runtime_error(std::string("checkpoint ") + path.string() + ": cannot read dataset " + name);
  return out;
}

void write_text(hid_t file, const std::string& name, const std::string& text) {
  // An empty text is one newline (HDF5 has no empty simple dataspace).
  const std::string t = text.empty() ? std::string("\n") : text;
  write_h5_dataset(file, name, H5T_NATIVE_CHAR, t.data(), t.size(), 1, "checkpoint");
}

}  // namespace

std::string scenario_fingerprint(const config::Scenario& scenario) {
  config::Scenario s = scenario;  // the accessors take a mutable scenario
  std::ostringstream out;
  out << "scene=" << s.scene << "\n";
  for (const config::Param& p : config::parameter_table()) {
    if (excluded(p.path)) continue;
    out << p.path << "=";
    switch (p.kind) {
      case config::Kind::kReal: out << exact(p.real(s)); break;
      case config::Kind::kInt: out << p.integer(s); break;
      case config::Kind::kBool: out << (p.boolean(s) ? "true" : "false"); break;
      case config::Kind::kChoice:
      case config::Kind::kString: out << p.choice(s); break;
      case config::Kind::kRealList:
        for (double v : p.real_list(s)) out << exact(v) << ",";
        break;
      case config::Kind::kChoiceList:
        for (const auto& v : p.choice_list(s)) out << v << ",";
        break;
    }
    out << "\n";
  }
  return out.str();
}

std::optional<fs::path> CheckpointDirectory::resumable() const {
  for (const char* name : {"latest", "old"}) {
    const fs::path d = root_ / name;
    std::error_code ec;
    if (fs::exists(d / "fluid.h5", ec) && fs::exists(d / "state.h5", ec)) return d;
  }
  return std::nullopt;
}

fs::path CheckpointDirectory::begin() {
  // A name of this process's own (rank 0's pid): a stale attempt of the same job that is still
  // running (its lease lost) cannot write into the same directory.
  std::string name = "next." + std::to_string(static_cast<long>(::getpid()));
  int ready = 0;
  MPI_Initialized(&ready);
  if (ready) {
    int n = static_cast<int>(name.size());
    MPI_Bcast(&n, 1, MPI_INT, 0, MPI_COMM_WORLD);
    name.resize(static_cast<std::size_t>(n));
    MPI_Bcast(name.data(), n, MPI_CHAR, 0, MPI_COMM_WORLD);
  }
  next_ = root_ / name;
  if (is_rank_zero()) {
    std::error_code ec;
    fs::remove_all(next_, ec);
    fs::create_directories(next_, ec);
    if (ec) throw std::runtime_error(std::string("checkpoint: cannot create ") + next_.string() + ": " + ec.message());
  }
  barrier();
  return next_;
}

void CheckpointDirectory::publish() {
  barrier();  // every rank's part of fluid.h5 is written
  if (is_rank_zero()) {
    std::error_code ec;
    const fs::path latest = root_ / "latest", old = root_ / "old";
    fs::remove_all(old, ec);
    if (fs::exists(latest, ec)) fs::rename(latest, old, ec);
    if (ec) throw std::runtime_error(std::string("checkpoint: cannot move ") + latest.string() + " aside: " + ec.message());
    fs::rename(next_, latest, ec);
    if (ec) throw std::runtime_error(std::string("checkpoint: cannot publish ") + next_.string() + ": " + ec.message());
    fs::remove_all(old, ec);
  }
  barrier();
}

void write_state_file(const fs::path& file, const StateArchive& archive, const std::string& fingerprint) {
  const hid_t f = H5Fcreate(file.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (f < 0) throw std::runtime_error(std::string("checkpoint: cannot create ") + file.string());
  try {
    // entry k: its name on line k of "names", its length in sizes[k], its values in "e<k>"
    // (one placeholder value for an empty entry: HDF5 has no empty simple dataspace)
    std::string names;
    std::vector<double> sizes;
    std::size_t k = 0;
    for (const auto& [name, values] : archive.entries()) {
      names += name + "\n";
      sizes.push_back(static_cast<double>(values.size()));
      const std::vector<double> data = values.empty() ? std::vector<double>{0.0} : values;
      write_h5_dataset(f, entry_name(k), H5T_NATIVE_DOUBLE, data.data(), data.size(), 1, "checkpoint");
      ++k;
    }
    if (sizes.empty()) sizes.push_back(0);
    write_h5_dataset(f, "sizes", H5T_NATIVE_DOUBLE, sizes.data(), sizes.size(), 1, "checkpoint");
    write_text(f, "names", names);
    write_text(f, "scenario", fingerprint);
  } catch (...) {
    H5Fclose(f);
    throw;
  }
  if (H5Fclose(f) < 0) throw std::runtime_error(std::string("checkpoint: cannot close ") + file.string());
}

StateArchive read_state_file(const fs::path& file, std::string& fingerprint) {
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (f < 0) throw std::runtime_error(std::string("checkpoint: cannot open ") + file.string());
  StateArchive a;
  try {
    const std::string names = read_text(f, "names", file);
    const std::vector<double> sizes = read_doubles(f, "sizes", file);
    std::istringstream in(names);
    std::size_t k = 0;
    for (std::string name; std::getline(in, name);) {
      if (name.empty()) continue;
      if (k >= sizes.size()) throw std::runtime_error(std::string("checkpoint ") + file.string() + ": more names than sizes");
      std::vector<double> v = read_doubles(f, entry_name(k), file);
      v.resize(static_cast<std::size_t>(sizes[k]));
      a.put(name, std::move(v));
      ++k;
    }
    fingerprint = read_text(f, "scenario", file);
  } catch (...) {
    H5Fclose(f);
    throw;
  }
  H5Fclose(f);
  return a;
}

void check_fingerprint(const fs::path& checkpoint, const std::string& stored, const std::string& current) {
  if (stored == current) return;
  auto path_of = [](const std::string& line) { return line.substr(0, line.find('=')); };
  auto refuse = [&](const std::string& there, const std::string& here, const std::string& why) {
    throw InputError(std::string("the checkpoint in ") + checkpoint.string() + " belongs to another scenario: it has " + there +
                     ", this scenario " + here + why + " (remove the checkpoint directory to start over)");
  };
  // A checkpoint written before a parameter was excluded still carries its line: skip it.
  auto lines = [&](const std::string& s) {
    std::vector<std::string> out;
    std::istringstream in(s);
    for (std::string l; std::getline(in, l);)
      if (!excluded(path_of(l))) out.push_back(l);
    return out;
  };
  // A checkpoint written before a field moved or was removed (config/removed_fields.h): a moved
  // field's line under its new path; a removed field's line dropped when it has the one value
  // every run used (its behaviour is the code's now), refused otherwise.
  std::vector<std::string> a;
  {
    std::istringstream in(stored);
    for (std::string l; std::getline(in, l);) {
      const std::string path = path_of(l);
      const config::RemovedField* gone = config::find_removed_field(path);
      if (gone == nullptr) {
        if (!excluded(path)) a.push_back(l);
      } else if (!gone->moved_to.empty()) {
        const std::string moved = std::string(gone->moved_to) + l.substr(path.size());
        if (!excluded(path_of(moved))) a.push_back(moved);
      } else if (l.substr(std::min(l.size(), path.size() + 1)) != gone->only_value) {
        refuse(l, "(nothing)", ": " + std::string(gone->path) + " was removed since (" + std::string(gone->why) + ")");
      }
    }
  }
  // A checkpoint written before a parameter existed has no line for it: the run it continues
  // had the parameter's default behaviour (a new parameter defaults to the old behaviour), so a
  // current line at the default value is skipped (ours).
  std::set<std::string> stored_paths;
  for (const auto& l : a) stored_paths.insert(path_of(l));
  std::set<std::string> defaults;
  for (const auto& l : lines(scenario_fingerprint(config::default_scenario()))) defaults.insert(l);
  std::vector<std::string> b;
  for (const auto& l : lines(current))
    if (stored_paths.count(path_of(l)) || !defaults.count(l)) b.push_back(l);
  // Compared by path (an older checkpoint's lines may come in another order); the first
  // difference named in this scenario's order.
  std::map<std::string, std::string> there_by_path, here_by_path;
  for (const auto& l : a) there_by_path[path_of(l)] = l;
  for (const auto& l : b) here_by_path[path_of(l)] = l;
  if (there_by_path == here_by_path) return;
  for (const auto& l : b) {
    const auto it = there_by_path.find(path_of(l));
    if (it == there_by_path.end())
      refuse("(nothing)", l, "");
    else if (it->second != l)
      refuse(it->second, l, "");
  }
  for (const auto& l : a)
    if (!here_by_path.count(path_of(l))) refuse(l, "(nothing)", "");
  refuse("(nothing)", "(nothing)", "");
}

}  // namespace systole::scene
