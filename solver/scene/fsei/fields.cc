#include "solver/scene/fsei/fields.h"

#include <hdf5.h>
#include <mpi.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "solver/diagnostics/phase_average.h"
#include "solver/geometry/left_heart.h"
#include "solver/scene/h5_dataset.h"

namespace systole::scene {
namespace {

constexpr const char* kBodiesFile = "fsei_bodies.h5";
constexpr const char* kXmfFile = "fsei_fields.xmf";

std::string fluid_file(int k) { return "fsei_fluid_" + std::to_string(k) + ".h5"; }

bool has_tension(const std::string& name) { return name == geometry::kLvBody || name == geometry::kLaBody; }

constexpr int kGzip = 4;  // the bodies' per-node arrays: shuffle + gzip level 4, as the fluid frames (ours)

std::vector<double> flat(const std::vector<geometry::Vec3>& v) {
  std::vector<double> out;
  out.reserve(3 * v.size());
  for (const auto& p : v) out.insert(out.end(), {p.x(), p.y(), p.z()});
  return out;
}

std::vector<std::int32_t> flat_triangles(const geometry::TriMesh& m) {
  std::vector<std::int32_t> tri;
  tri.reserve(3 * m.triangle_count());
  for (const auto& t : m.tri) tri.insert(tri.end(), t.begin(), t.end());
  return tri;
}

// XDMF items pointing into an HDF5 file: n nodal values of comps components (doubles), and a
// triangle topology of nt triangles (int32 rows).
std::string xdmf_nodes(std::size_t n, int comps, const std::string& file, const std::string& set) {
  std::ostringstream d;
  d << "<DataItem Dimensions=\"" << n;
  if (comps > 1) d << ' ' << comps;
  d << "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << file << ":/" << set << "</DataItem>";
  return d.str();
}
std::string xdmf_triangles(std::size_t nt, const std::string& file, const std::string& set) {
  return "<Topology TopologyType=\"Triangle\" NumberOfElements=\"" + std::to_string(nt) + "\"><DataItem Dimensions=\"" +
         std::to_string(nt) + " 3\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">" + file + ":/" + set +
         "</DataItem></Topology>\n";
}

}  // namespace

FseiFieldWriter::FseiFieldWriter(std::filesystem::path dir, const grid::Grid& grid, double mm_per_unit,
                                 const geometry::TriMesh& plane, const structure::BodyGroup& group,
                                 std::vector<std::string> names, fluid::FluidSolver::FieldSelection fluid_units,
                                 std::function<std::vector<double>(std::size_t)> node_vm_mv,
                                 const std::vector<double>* resumed_times_ms)
    : dir_(std::move(dir)),
      nx_(grid.nx()),
      ny_(grid.ny()),
      nz_(grid.nz()),
      dx_mm_(grid.dx() * mm_per_unit),
      dy_mm_(grid.dy() * mm_per_unit),
      dz_mm_(grid.dz() * mm_per_unit),
      names_(std::move(names)),
      plane_nodes_(plane.node_count()),
      plane_triangles_(plane.triangle_count()),
      plane_(plane),
      group_(group),
      units_(fluid_units),
      node_vm_mv_(std::move(node_vm_mv)),
      rank0_(is_rank_zero()) {
  if (names_.size() != group.body_count())
    throw std::invalid_argument("FseiFieldWriter: " + std::to_string(names_.size()) + " names for " +
                                std::to_string(group.body_count()) + " bodies");
  units_.write_xdmf = false;
  for (std::size_t b = 0; b < group.body_count(); ++b) {
    triangles_.push_back(group.body(b).stress_free_mesh().triangle_count());
    nodes_.push_back(group.body(b).node_count());
  }
  const std::string path = (dir_ / kBodiesFile).string();
  if (resumed_times_ms) {
    // the earlier frames count as present when the bodies file holds every one of them (rank
    // 0 looks, every rank learns the answer)
    int present = 0;
    if (rank0_) {
      std::error_code ec;
      if (std::filesystem::exists(path, ec)) {
        const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
        present = file >= 0 ? 1 : 0;
        for (std::size_t k = 0; present && k < resumed_times_ms->size(); ++k)
          present = H5Lexists(file, ("frames/" + std::to_string(k)).c_str(), H5P_DEFAULT) > 0 ? 1 : 0;
        if (file >= 0) H5Fclose(file);
      }
    }
    int ready = 0;
    MPI_Initialized(&ready);
    if (ready) MPI_Bcast(&present, 1, MPI_INT, 0, MPI_COMM_WORLD);
    earlier_present_ = present != 0;
    for (double t : *resumed_times_ms) frames_.push_back({t, true, "", earlier_present_});
  }
  if (!rank0_) return;
  std::filesystem::create_directories(dir_);
  if (!resumed_times_ms || !earlier_present_) {
    create_bodies_file();
  } else {
    const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    if (file < 0) throw std::runtime_error("fsei fields: cannot open " + path);
    for (std::size_t k = resumed_times_ms->size();; ++k) {  // the interrupted attempt's later frames
      const std::string g = "frames/" + std::to_string(k);
      if (H5Lexists(file, g.c_str(), H5P_DEFAULT) <= 0) break;
      H5Ldelete(file, g.c_str(), H5P_DEFAULT);
    }
    H5Fclose(file);
  }
  if (resumed_times_ms) write_xmf();
}

void FseiFieldWriter::create_bodies_file() const {
  const geometry::TriMesh& plane = plane_;
  const structure::BodyGroup& group = group_;
  const std::string path = (dir_ / kBodiesFile).string();
  const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (file < 0) throw std::runtime_error("fsei fields: cannot create " + path);
  H5Gclose(H5Gcreate2(file, "mesh", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  H5Gclose(H5Gcreate2(file, "frames", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  auto triangles = [&](const geometry::TriMesh& m, const std::string& name) {
    const std::vector<std::int32_t> tri = flat_triangles(m);
    write_h5_dataset(file, "mesh/" + name + "_triangles", H5T_NATIVE_INT32, tri.data(), m.triangle_count(), 3,
                     "fsei fields");
  };
  triangles(plane, std::string(geometry::kValvularPlaneBody));
  const std::vector<double> xp = flat(plane.position_mm);
  write_h5_dataset(file, "mesh/" + std::string(geometry::kValvularPlaneBody) + "_positions_mm", H5T_NATIVE_DOUBLE,
                   xp.data(), plane.node_count(), 3, "fsei fields");
  for (std::size_t b = 0; b < group.body_count(); ++b) triangles(group.body(b).stress_free_mesh(), names_[b]);
  H5Fclose(file);
}

std::vector<double> FseiFieldWriter::frame_times_ms() const {
  std::vector<double> t;
  for (const Frame& f : frames_) t.push_back(f.time_ms);
  return t;
}

void FseiFieldWriter::write_bodies(int k, double time_ms, const structure::BodyGroup& group,
                                  const std::vector<std::vector<double>>* wss_pa) const {
  const std::string path = (dir_ / kBodiesFile).string();
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  if (file < 0) throw std::runtime_error("fsei fields: cannot open " + path);
  const std::string g = "frames/" + std::to_string(k);
  H5Gclose(H5Gcreate2(file, g.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  write_h5_dataset(file, g + "/time_ms", H5T_NATIVE_DOUBLE, &time_ms, 1, 1, "fsei fields");
  for (std::size_t b = 0; b < group.body_count(); ++b) {
    const structure::ShellModel& m = group.body(b);
    const std::string n = g + "/" + names_[b];
    const std::vector<double> x = flat(m.positions_mm()), v = flat(m.velocities_mm_per_ms());  // mm/ms = m/s
    write_h5_dataset(file, n + "_positions_mm", H5T_NATIVE_DOUBLE, x.data(), m.node_count(), 3, "fsei fields", kGzip);
    write_h5_dataset(file, n + "_velocity_m_s", H5T_NATIVE_DOUBLE, v.data(), m.node_count(), 3, "fsei fields", kGzip);
    std::vector<double> worst(m.node_count(), 0.0);
    const std::vector<double> eps = m.edge_strains();
    const auto& springs = m.springs();
    for (std::size_t e = 0; e < springs.size(); ++e)
      for (std::int32_t i : {springs[e].i, springs[e].j}) {
        double& w = worst[static_cast<std::size_t>(i)];
        if (!(std::abs(eps[e]) <= std::abs(w))) w = eps[e];  // a NaN strain is kept: it is the diagnosis
      }
    write_h5_dataset(file, n + "_edge_strain", H5T_NATIVE_DOUBLE, worst.data(), m.node_count(), 1, "fsei fields", kGzip);
    if (has_tension(names_[b])) {
      write_h5_dataset(file, n + "_active_tension_kpa", H5T_NATIVE_DOUBLE, m.active_tension_kpa().data(),
                       m.node_count(), 1, "fsei fields", kGzip);
      if (node_vm_mv_) {
        const std::vector<double> vm = node_vm_mv_(b);
        if (vm.size() != m.node_count()) throw std::logic_error("fsei fields: vm_mv of " + names_[b] + " has the wrong size");
        write_h5_dataset(file, n + "_vm_mv", H5T_NATIVE_DOUBLE, vm.data(), m.node_count(), 1, "fsei fields", kGzip);
      }
    }
    if (wss_pa) {
      if (wss_pa->at(b).size() != m.node_count()) throw std::logic_error("fsei fields: wss_pa of " + names_[b] + " has the wrong size");
      write_h5_dataset(file, n + "_wss_pa", H5T_NATIVE_DOUBLE, wss_pa->at(b).data(), m.node_count(), 1, "fsei fields", kGzip);
    }
  }
  H5Fclose(file);
}

void FseiFieldWriter::frame(double time_ms, const fluid::FluidSolver& fluid, const structure::BodyGroup& group,
                            const std::vector<std::vector<double>>& wss_pa) {
  const int k = frames();
  fluid.write_fields(dir_ / fluid_file(k), units_);
  frames_.push_back({time_ms, true, ""});
  if (!rank0_) return;
  write_bodies(k, time_ms, group, &wss_pa);
  write_xmf();
}

void FseiFieldWriter::bodies_frame(double time_ms, const structure::BodyGroup& group, const std::string& label) {
  const int k = frames();
  frames_.push_back({time_ms, false, label});
  if (!rank0_) return;
  write_bodies(k, time_ms, group, nullptr);
  write_xmf();
}

void FseiFieldWriter::write_xmf() const {
  const std::filesystem::path xmf = dir_ / kXmfFile;
  const std::filesystem::path tmp = dir_ / (std::string(kXmfFile) + ".tmp");
  {
    std::ofstream x(tmp);
    if (!x) throw std::runtime_error("fsei fields: cannot write " + tmp.string());
    x.precision(10);
    const std::string dims = std::to_string(nz_) + " " + std::to_string(ny_) + " " + std::to_string(nx_);
    auto cells = [&](const std::string& file, const std::string& set) {
      return "<DataItem Dimensions=\"" + dims + "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" + file +
             ":/" + set + "</DataItem>";
    };
    auto nodes = [&](std::size_t n, int comps, const std::string& set) { return xdmf_nodes(n, comps, kBodiesFile, set); };
    auto topology = [&](std::size_t nt, const std::string& name) {
      return xdmf_triangles(nt, kBodiesFile, "mesh/" + name + "_triangles");
    };
    x << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n"
      << "  <Grid Name=\"fsei\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
    for (std::size_t k = 0; k < frames_.size(); ++k) {
      const Frame& f = frames_[k];
      if (!f.present) continue;
      std::string frame_name = "frame" + std::to_string(k);
      if (!f.label.empty()) frame_name.append(" ").append(f.label);
      x << "   <Grid Name=\"" << frame_name << "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n    <Time Value=\""
        << f.time_ms << "\"/>\n";
      if (f.fluid) {
        const std::string file = fluid_file(static_cast<int>(k));
        x << "    <Grid Name=\"fluid\" GridType=\"Uniform\">\n"
          << "     <Topology TopologyType=\"3DCoRectMesh\" Dimensions=\"" << dims << "\"/>\n"
          << "     <Geometry GeometryType=\"ORIGIN_DXDYDZ\">\n"
          << "      <DataItem Dimensions=\"3\" NumberType=\"Float\" Format=\"XML\">" << dz_mm_ / 2 << " " << dy_mm_ / 2
          << " " << dx_mm_ / 2 << "</DataItem>\n"
          << "      <DataItem Dimensions=\"3\" NumberType=\"Float\" Format=\"XML\">" << dz_mm_ << " " << dy_mm_ << " "
          << dx_mm_ << "</DataItem>\n     </Geometry>\n";
        if (units_.pressure)
          x << "     <Attribute Name=\"pressure_mmhg\" AttributeType=\"Scalar\" Center=\"Node\">" << cells(file, "pressure")
            << "</Attribute>\n";
        for (const auto& [on, name, base] : {std::tuple{units_.velocity, "velocity_m_s", "velocity"},
                                             std::tuple{units_.vorticity, "vorticity_per_s", "vorticity"}}) {
          if (!on) continue;
          const std::string b = base;
          x << "     <Attribute Name=\"" << name << "\" AttributeType=\"Vector\" Center=\"Node\">\n"
            << "      <DataItem ItemType=\"Function\" Function=\"JOIN($0, $1, $2)\" Dimensions=\"" << dims << " 3\">\n"
            << "       " << cells(file, b + "_x") << "\n       " << cells(file, b + "_y") << "\n       "
            << cells(file, b + "_z") << "\n      </DataItem>\n     </Attribute>\n";
        }
        x << "    </Grid>\n";
      }
      const std::string plane(geometry::kValvularPlaneBody);
      x << "    <Grid Name=\"" << plane << "\" GridType=\"Uniform\">\n     " << topology(plane_triangles_, plane)
        << "     <Geometry GeometryType=\"XYZ\">" << nodes(plane_nodes_, 3, "mesh/" + plane + "_positions_mm")
        << "</Geometry>\n    </Grid>\n";
      for (std::size_t b = 0; b < names_.size(); ++b) {
        const std::string p = "frames/" + std::to_string(k) + "/" + names_[b];
        x << "    <Grid Name=\"" << names_[b] << "\" GridType=\"Uniform\">\n     " << topology(triangles_[b], names_[b])
          << "     <Geometry GeometryType=\"XYZ\">" << nodes(nodes_[b], 3, p + "_positions_mm") << "</Geometry>\n"
          << "     <Attribute Name=\"velocity_m_s\" AttributeType=\"Vector\" Center=\"Node\">"
          << nodes(nodes_[b], 3, p + "_velocity_m_s") << "</Attribute>\n"
          << "     <Attribute Name=\"edge_strain\" AttributeType=\"Scalar\" Center=\"Node\">"
          << nodes(nodes_[b], 1, p + "_edge_strain") << "</Attribute>\n";
        if (has_tension(names_[b]))
          x << "     <Attribute Name=\"active_tension_kpa\" AttributeType=\"Scalar\" Center=\"Node\">"
            << nodes(nodes_[b], 1, p + "_active_tension_kpa") << "</Attribute>\n";
        if (has_tension(names_[b]) && node_vm_mv_)
          x << "     <Attribute Name=\"vm_mv\" AttributeType=\"Scalar\" Center=\"Node\">"
            << nodes(nodes_[b], 1, p + "_vm_mv") << "</Attribute>\n";
        if (frames_[k].fluid)
          x << "     <Attribute Name=\"wss_pa\" AttributeType=\"Scalar\" Center=\"Node\">"
            << nodes(nodes_[b], 1, p + "_wss_pa") << "</Attribute>\n";
        x << "    </Grid>\n";
      }
      x << "   </Grid>\n";
    }
    x << "  </Grid>\n </Domain>\n</Xdmf>\n";
  }
  std::filesystem::rename(tmp, xmf);
}

void write_wss_phase_average(const std::filesystem::path& dir, const structure::BodyGroup& group,
                             const std::vector<std::string>& names, const diagnostics::FieldPhaseAverage& wss) {
  const char* owner = "fsei wss phase average";
  const std::string h5name = "fsei_wss_phase.h5";
  const std::string path = (dir / h5name).string();
  std::error_code made;  // the output directory may not exist yet (fsei_case out=DIR; a missing one once cost a run its end)
  std::filesystem::create_directories(dir, made);
  const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (file < 0)
    throw std::runtime_error(std::string(owner) + ": cannot create " + path +
                             (made ? " (the directory: " + made.message() + ")" : std::string()));
  const int bins = wss.bins();
  std::vector<double> phase(static_cast<std::size_t>(bins)), beats(static_cast<std::size_t>(bins));
  for (int j = 0; j < bins; ++j) {
    phase[static_cast<std::size_t>(j)] = (j + 0.5) / bins;
    beats[static_cast<std::size_t>(j)] = wss.beats(j);
  }
  write_h5_dataset(file, "phase", H5T_NATIVE_DOUBLE, phase.data(), static_cast<hsize_t>(bins), 1, owner);
  write_h5_dataset(file, "beats", H5T_NATIVE_DOUBLE, beats.data(), static_cast<hsize_t>(bins), 1, owner);
  std::vector<std::vector<double>> mean, rms;
  for (int j = 0; j < bins; ++j) {
    mean.push_back(wss.mean(j));
    rms.push_back(wss.rms(j));
  }
  std::size_t offset = 0;
  for (std::size_t b = 0; b < group.body_count(); ++b) {
    const geometry::TriMesh& m = group.body(b).stress_free_mesh();
    const std::string& n = names.at(b);
    H5Gclose(H5Gcreate2(file, n.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    const std::vector<std::int32_t> tri = flat_triangles(m);
    write_h5_dataset(file, n + "/triangles", H5T_NATIVE_INT32, tri.data(), m.triangle_count(), 3, owner);
    const std::vector<double> x = flat(m.position_mm);
    write_h5_dataset(file, n + "/positions_mm", H5T_NATIVE_DOUBLE, x.data(), m.node_count(), 3, owner);
    for (int j = 0; j < bins; ++j) {
      const std::string g = n + "/bin_" + std::to_string(j);
      H5Gclose(H5Gcreate2(file, g.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
      const auto jj = static_cast<std::size_t>(j);
      write_h5_dataset(file, g + "/wss_mean_pa", H5T_NATIVE_DOUBLE, mean[jj].data() + offset, m.node_count(), 1, owner);
      write_h5_dataset(file, g + "/wss_rms_pa", H5T_NATIVE_DOUBLE, rms[jj].data() + offset, m.node_count(), 1, owner);
    }
    offset += m.node_count();
  }
  H5Fclose(file);
  // ParaView: a temporal collection over the phase bins (time = t/T), every body in each;
  // written to a temporary name and renamed, as the frames' xmf.
  const std::filesystem::path xmf = dir / "fsei_wss_phase.xmf", tmp = dir / "fsei_wss_phase.xmf.tmp";
  std::ofstream x(tmp);
  x << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\"><Domain>\n"
    << "<Grid Name=\"wss_phase_average\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (int j = 0; j < bins; ++j) {
    x << "<Grid Name=\"bin_" << j << "\" GridType=\"Collection\" CollectionType=\"Spatial\"><Time Value=\""
      << phase[static_cast<std::size_t>(j)] << "\"/>\n";
    for (std::size_t b = 0; b < group.body_count(); ++b) {
      const geometry::TriMesh& m = group.body(b).stress_free_mesh();
      const std::string& n = names[b];
      x << "<Grid Name=\"" << n << "\">" << xdmf_triangles(m.triangle_count(), h5name, n + "/triangles")
        << "<Geometry GeometryType=\"XYZ\">" << xdmf_nodes(m.node_count(), 3, h5name, n + "/positions_mm")
        << "</Geometry>\n";
      for (const char* a : {"wss_mean_pa", "wss_rms_pa"})
        x << "<Attribute Name=\"" << a << "\" Center=\"Node\">"
          << xdmf_nodes(m.node_count(), 1, h5name, n + "/bin_" + std::to_string(j) + "/" + a) << "</Attribute>\n";
      x << "</Grid>\n";
    }
    x << "</Grid>\n";
  }
  x << "</Grid>\n</Domain></Xdmf>\n";
  x.close();
  if (!x) throw std::runtime_error(std::string(owner) + ": cannot write " + tmp.string());
  std::filesystem::rename(tmp, xmf);
}

}  // namespace systole::scene
