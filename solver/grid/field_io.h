#pragma once
// HDF5 I/O of grid fields (parallel HDF5, one file shared by all ranks of the slabs) and the
// XDMF sidecar that lets ParaView open cell-centred fields. Every field is stored as a global
// dataset [nz][ny][nx] (x fastest) of its interior values, whatever its location; the
// location is recorded in the dataset attribute "location". (ours) This lives in grid/ rather
// than io/ because it needs the slab layout; io/ may wrap it.
#include <filesystem>
#include <string>
#include <vector>

#include "solver/grid/grid.h"

namespace systole::grid {

// An open HDF5 file. Constructor and destructor are collective on slabs.comm(); so is every
// call. Throws std::runtime_error on I/O failure (file named in the message).
class FieldFile {
 public:
  enum class Mode { create, read };
  FieldFile(const std::filesystem::path& file, const Slabs& slabs, Mode mode);
  ~FieldFile();
  FieldFile(const FieldFile&) = delete;
  FieldFile& operator=(const FieldFile&) = delete;

  template <Location L>
  void write(const std::string& name, const Field<L>& f) {
    write_raw(name, f.data(), L);
  }
  // Reads the interior; halos are left as they were (exchange them afterwards).
  template <Location L>
  void read(const std::string& name, Field<L>& f) const {
    read_raw(name, f.data(), L);
  }
  // Datasets written after this are chunked (up to 8 z-planes per chunk) and compressed with
  // shuffle + gzip at this level (1-9; 0: contiguous, uncompressed, the default). Collective
  // writes of filtered datasets need parallel HDF5 >= 1.10.2 (Debian 12 has 1.10.8).
  void set_compression(int gzip_level);
  void write_attribute(const std::string& name, double value);
  double read_attribute(const std::string& name) const;

 private:
  void write_raw(const std::string& name, const double* data, Location location);
  void read_raw(const std::string& name, double* data, Location location) const;
  std::filesystem::path path_;
  const Slabs& slabs_;
  long long file_ = -1;  // hid_t
  int gzip_level_ = 0;
};

// XDMF 2 for the cell-centred datasets `scalars` (and the 3-component `vectors`, each given as
// three dataset names) of `h5_file` (a path relative to the xdmf file). Rank 0 writes.
struct XdmfVector {
  std::string name;
  std::string x, y, z;  // dataset names
};
void write_xdmf(const std::filesystem::path& xdmf_file, const std::string& h5_file, const Grid& grid,
                const std::vector<std::string>& scalars, const std::vector<XdmfVector>& vectors,
                double time);

}  // namespace systole::grid
