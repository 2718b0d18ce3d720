#include "solver/grid/field_io.h"

#include <hdf5.h>

#include <algorithm>
#include <fstream>
#include <stdexcept>

namespace systole::grid {

namespace {
[[noreturn]] void fail(const std::filesystem::path& file, const std::string& what) {
  throw std::runtime_error("HDF5 " + what + " failed on " + file.string());
}
}  // namespace

FieldFile::FieldFile(const std::filesystem::path& file, const Slabs& slabs, Mode mode)
    : path_(file), slabs_(slabs) {
  hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  H5Pset_fapl_mpio(fapl, slabs.comm(), MPI_INFO_NULL);
  hid_t f = mode == Mode::create ? H5Fcreate(file.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl)
                                 : H5Fopen(file.c_str(), H5F_ACC_RDONLY, fapl);
  H5Pclose(fapl);
  if (f < 0) fail(file, mode == Mode::create ? "create" : "open");
  file_ = f;
}

FieldFile::~FieldFile() {
  if (file_ >= 0) H5Fclose(static_cast<hid_t>(file_));
}

namespace {
// Memory space: the whole halo'd local array, the interior selected.
hid_t memory_space(const Slabs& slabs) {
  const Grid& g = slabs.grid();
  hsize_t dims[3] = {static_cast<hsize_t>(slabs.k_count() + 2), static_cast<hsize_t>(g.ny() + 2),
                     static_cast<hsize_t>(g.nx() + 2)};
  hid_t space = H5Screate_simple(3, dims, nullptr);
  hsize_t start[3] = {1, 1, 1};
  hsize_t count[3] = {static_cast<hsize_t>(slabs.k_count()), static_cast<hsize_t>(g.ny()),
                      static_cast<hsize_t>(g.nx())};
  H5Sselect_hyperslab(space, H5S_SELECT_SET, start, nullptr, count, nullptr);
  return space;
}
void select_slab(hid_t file_space, const Slabs& slabs) {
  const Grid& g = slabs.grid();
  hsize_t start[3] = {static_cast<hsize_t>(slabs.k_begin()), 0, 0};
  hsize_t count[3] = {static_cast<hsize_t>(slabs.k_count()), static_cast<hsize_t>(g.ny()),
                      static_cast<hsize_t>(g.nx())};
  H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start, nullptr, count, nullptr);
}
}  // namespace

void FieldFile::write_raw(const std::string& name, const double* data, Location location) {
  const Grid& g = slabs_.grid();
  hsize_t dims[3] = {static_cast<hsize_t>(g.nz()), static_cast<hsize_t>(g.ny()),
                     static_cast<hsize_t>(g.nx())};
  hid_t file_space = H5Screate_simple(3, dims, nullptr);
  hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
  if (gzip_level_ > 0) {
    const hsize_t chunk[3] = {std::min<hsize_t>(dims[0], 8), dims[1], dims[2]};
    H5Pset_chunk(dcpl, 3, chunk);
    H5Pset_shuffle(dcpl);
    H5Pset_deflate(dcpl, static_cast<unsigned>(gzip_level_));
  }
  hid_t set = H5Dcreate2(static_cast<hid_t>(file_), name.c_str(), H5T_NATIVE_DOUBLE, file_space,
                         H5P_DEFAULT, dcpl, H5P_DEFAULT);
  H5Pclose(dcpl);
  if (set < 0) fail(path_, "create dataset " + name);
  select_slab(file_space, slabs_);
  hid_t mem = memory_space(slabs_);
  hid_t xfer = H5Pcreate(H5P_DATASET_XFER);
  H5Pset_dxpl_mpio(xfer, H5FD_MPIO_COLLECTIVE);
  herr_t status = H5Dwrite(set, H5T_NATIVE_DOUBLE, mem, file_space, xfer, data);
  // The location tag, as a string attribute.
  const std::string loc = to_string(location);
  hid_t str = H5Tcopy(H5T_C_S1);
  H5Tset_size(str, loc.size());
  hid_t scalar = H5Screate(H5S_SCALAR);
  hid_t attr = H5Acreate2(set, "location", str, scalar, H5P_DEFAULT, H5P_DEFAULT);
  H5Awrite(attr, str, loc.c_str());
  H5Aclose(attr);
  H5Sclose(scalar);
  H5Tclose(str);
  H5Pclose(xfer);
  H5Sclose(mem);
  H5Sclose(file_space);
  H5Dclose(set);
  if (status < 0) fail(path_, "write dataset " + name);
}

void FieldFile::read_raw(const std::string& name, double* data, Location) const {
  hid_t set = H5Dopen2(static_cast<hid_t>(file_), name.c_str(), H5P_DEFAULT);
  if (set < 0) fail(path_, "open dataset " + name);
  hid_t file_space = H5Dget_space(set);
  hsize_t dims[3];
  const Grid& g = slabs_.grid();
  if (H5Sget_simple_extent_ndims(file_space) != 3 || (H5Sget_simple_extent_dims(file_space, dims, nullptr),
      dims[0] != static_cast<hsize_t>(g.nz()) || dims[1] != static_cast<hsize_t>(g.ny()) ||
      dims[2] != static_cast<hsize_t>(g.nx()))) {
    H5Sclose(file_space);
    H5Dclose(set);
    fail(path_, "shape check (grid mismatch) of dataset " + name);
  }
  select_slab(file_space, slabs_);
  hid_t mem = memory_space(slabs_);
  hid_t xfer = H5Pcreate(H5P_DATASET_XFER);
  H5Pset_dxpl_mpio(xfer, H5FD_MPIO_COLLECTIVE);
  herr_t status = H5Dread(set, H5T_NATIVE_DOUBLE, mem, file_space, xfer, data);
  H5Pclose(xfer);
  H5Sclose(mem);
  H5Sclose(file_space);
  H5Dclose(set);
  if (status < 0) fail(path_, "read dataset " + name);
}

void FieldFile::set_compression(int gzip_level) {
  if (gzip_level < 0 || gzip_level > 9)
    throw std::invalid_argument("FieldFile::set_compression: gzip level " + std::to_string(gzip_level) +
                                " outside [0, 9]");
  gzip_level_ = gzip_level;
}

void FieldFile::write_attribute(const std::string& name, double value) {
  hid_t scalar = H5Screate(H5S_SCALAR);
  hid_t attr = H5Acreate2(static_cast<hid_t>(file_), name.c_str(), H5T_NATIVE_DOUBLE, scalar,
                          H5P_DEFAULT, H5P_DEFAULT);
  if (attr < 0) fail(path_, "create attribute " + name);
  herr_t status = H5Awrite(attr, H5T_NATIVE_DOUBLE, &value);
  H5Aclose(attr);
  H5Sclose(scalar);
  if (status < 0) fail(path_, "write attribute " + name);
}

double FieldFile::read_attribute(const std::string& name) const {
  hid_t attr = H5Aopen(static_cast<hid_t>(file_), name.c_str(), H5P_DEFAULT);
  if (attr < 0) fail(path_, "open attribute " + name);
  double value = 0;
  herr_t status = H5Aread(attr, H5T_NATIVE_DOUBLE, &value);
  H5Aclose(attr);
  if (status < 0) fail(path_, "read attribute " + name);
  return value;
}

void write_xdmf(const std::filesystem::path& xdmf_file, const std::string& h5_file, const Grid& g,
                const std::vector<std::string>& scalars, const std::vector<XdmfVector>& vectors,
                double time) {
  std::ofstream out(xdmf_file);
  if (!out) throw std::runtime_error("cannot write " + xdmf_file.string());
  const std::string dims =
      std::to_string(g.nz()) + " " + std::to_string(g.ny()) + " " + std::to_string(g.nx());
  auto item = [&](const std::string& set) {
    return "<DataItem Dimensions=\"" + dims + "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" +
           h5_file + ":/" + set + "</DataItem>";
  };
  out.precision(17);
  out << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"2.0\">\n<Domain>\n<Grid Name=\"fluid\" GridType=\"Uniform\">\n"
      << "<Time Value=\"" << time << "\"/>\n"
      << "<Topology TopologyType=\"3DCoRectMesh\" Dimensions=\"" << dims << "\"/>\n"
      << "<Geometry GeometryType=\"ORIGIN_DXDYDZ\">\n"
      << "<DataItem Dimensions=\"3\" NumberType=\"Float\" Format=\"XML\">" << g.dz() / 2 << " "
      << g.dy() / 2 << " " << g.dx() / 2 << "</DataItem>\n"
      << "<DataItem Dimensions=\"3\" NumberType=\"Float\" Format=\"XML\">" << g.dz() << " " << g.dy()
      << " " << g.dx() << "</DataItem>\n</Geometry>\n";
  for (const auto& s : scalars)
    out << "<Attribute Name=\"" << s << "\" AttributeType=\"Scalar\" Center=\"Node\">\n" << item(s) << "\n</Attribute>\n";
  for (const auto& v : vectors) {
    out << "<Attribute Name=\"" << v.name << "\" AttributeType=\"Vector\" Center=\"Node\">\n"
        << "<DataItem ItemType=\"Function\" Function=\"JOIN($0, $1, $2)\" Dimensions=\"" << dims
        << " 3\">\n" << item(v.x) << "\n" << item(v.y) << "\n" << item(v.z) << "\n</DataItem>\n</Attribute>\n";
  }
  out << "</Grid>\n</Domain>\n</Xdmf>\n";
}

}  // namespace systole::grid
