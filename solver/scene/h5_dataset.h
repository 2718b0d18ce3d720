#pragma once
// One HDF5 dataset, 1-D (cols = 1) or rows × cols, written in one call: the nodal fields the
// scenes' XDMF files point at. gzip_level in [1, 9] stores it as one chunk with the shuffle and
// gzip filters (HDF5 records the filters in the dataset: `h5dump -p`); 0 (default) uncompressed.
// Throws std::runtime_error naming `owner` and the dataset.
#include <hdf5.h>
#include <mpi.h>

#include <stdexcept>
#include <string>

namespace systole::scene {

inline void write_h5_dataset(hid_t file, const std::string& name, hid_t type, const void* data, hsize_t rows,
                             hsize_t cols, const char* owner, int gzip_level = 0) {
  if (gzip_level < 0 || gzip_level > 9)
    throw std::invalid_argument(std::string(owner) + ": gzip level " + std::to_string(gzip_level) + " outside [0, 9]");
  const hsize_t dims[2] = {rows, cols};
  const int rank = cols > 1 ? 2 : 1;
  const hid_t space = H5Screate_simple(rank, dims, nullptr);
  const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
  if (gzip_level > 0 && rows > 0 && cols > 0) {
    H5Pset_chunk(dcpl, rank, dims);
    H5Pset_shuffle(dcpl);
    H5Pset_deflate(dcpl, static_cast<unsigned>(gzip_level));
  }
  const hid_t set = H5Dcreate2(file, name.c_str(), type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  H5Pclose(dcpl);
  const bool ok = set >= 0 && H5Dwrite(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0;
  if (set >= 0) H5Dclose(set);
  H5Sclose(space);
  if (!ok) throw std::runtime_error(std::string(owner) + ": cannot write HDF5 dataset " + name);
}

// True on MPI rank 0 of MPI_COMM_WORLD, or when MPI is not initialised: the rank that writes a
// scene's serial output files (every rank runs the same serial solve).
inline bool is_rank_zero() {
  int ready = 0;
  MPI_Initialized(&ready);
  if (!ready) return true;
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return rank == 0;
}

}  // namespace systole::scene
