#include "solver/geometry/mesh_io.h"

#include <hdf5.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <unordered_map>

#include <nlohmann/json.hpp>

#include "solver/core/errors.h"

namespace systole::geometry {

namespace fs = std::filesystem;

namespace {

[[noreturn]] void fail(const fs::path& path, const std::string& what) {
  throw InputError("cannot read mesh '" + path.string() + "': " + what);
}

std::string read_all(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open the file");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Merges exactly coincident vertices (STL stores every triangle corner separately).
struct VertexMerger {
  TriMesh& mesh;
  std::map<std::array<double, 3>, std::int32_t> index;
  std::int32_t get(const Vec3& p) {
    const std::array<double, 3> key{p.x(), p.y(), p.z()};
    auto it = index.find(key);
    if (it != index.end()) return it->second;
    const auto id = mesh.add_node(p);
    index.emplace(key, id);
    return id;
  }
};

void add_default_triangle(TriMesh& mesh, std::int32_t a, std::int32_t b, std::int32_t c) {
  mesh.add_triangle(a, b, c, Tissue::kLvMyocardium, 1.0, Vec3::Zero());
}

std::string body_name_of(const fs::path& path) { return path.stem().string(); }

}  // namespace

TriMesh read_stl(const fs::path& path) {
  const std::string data = read_all(path);
  TriMesh mesh;
  mesh.name = body_name_of(path);
  VertexMerger merge{mesh, {}};
  bool binary = false;
  if (data.size() >= 84) {
    std::uint32_t n;
    std::memcpy(&n, data.data() + 80, 4);
    binary = data.size() == 84 + 50ull * n;
  }
  if (binary) {
    std::uint32_t n;
    std::memcpy(&n, data.data() + 80, 4);
    for (std::uint32_t t = 0; t < n; ++t) {
      const char* rec = data.data() + 84 + 50ull * t;
      std::int32_t id[3];
      for (int k = 0; k < 3; ++k) {
        float v[3];
        std::memcpy(v, rec + 12 + 12 * k, 12);
        id[k] = merge.get(Vec3(v[0], v[1], v[2]));
      }
      add_default_triangle(mesh, id[0], id[1], id[2]);
    }
    return mesh;
  }
  if (data.compare(0, 5, "solid") != 0)
    fail(path, "neither binary STL (size != 84 + 50 n) nor ASCII STL (no leading 'solid')");
  std::istringstream in(data);
  std::string word;
  std::vector<std::int32_t> corners;
  std::size_t line_guess = 0;
  while (in >> word) {
    if (word == "vertex") {
      double x, y, z;
      if (!(in >> x >> y >> z)) fail(path, "bad 'vertex' record after " + std::to_string(line_guess) + " vertices");
      corners.push_back(merge.get(Vec3(x, y, z)));
      ++line_guess;
    } else if (word == "endloop") {
      if (corners.size() < 3) fail(path, "a facet with fewer than 3 vertices");
      for (std::size_t k = 1; k + 1 < corners.size(); ++k)
        add_default_triangle(mesh, corners[0], corners[k], corners[k + 1]);
      corners.clear();
    }
  }
  if (mesh.tri.empty()) fail(path, "no facets");
  return mesh;
}

TriMesh read_obj(const fs::path& path) {
  std::ifstream in(path);
  if (!in) fail(path, "cannot open the file");
  TriMesh mesh;
  mesh.name = body_name_of(path);
  std::string line;
  std::size_t lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    std::istringstream s(line);
    std::string tag;
    if (!(s >> tag)) continue;
    if (tag == "v") {
      double x, y, z;
      if (!(s >> x >> y >> z)) fail(path, "line " + std::to_string(lineno) + ": bad vertex");
      mesh.add_node(Vec3(x, y, z));
    } else if (tag == "f") {
      std::vector<std::int32_t> ids;
      std::string item;
      while (s >> item) {
        const long v = std::strtol(item.c_str(), nullptr, 10);  // "i", "i/t", "i//n", "i/t/n"
        const long n = static_cast<long>(mesh.node_count());
        const long id = v < 0 ? n + v : v - 1;
        if (v == 0 || id < 0 || id >= n)
          fail(path, "line " + std::to_string(lineno) + ": vertex index " + item + " out of range");
        ids.push_back(static_cast<std::int32_t>(id));
      }
      if (ids.size() < 3) fail(path, "line " + std::to_string(lineno) + ": face with fewer than 3 vertices");
      for (std::size_t k = 1; k + 1 < ids.size(); ++k) add_default_triangle(mesh, ids[0], ids[k], ids[k + 1]);
    }
  }
  if (mesh.tri.empty()) fail(path, "no faces");
  return mesh;
}

namespace {

// Values of a legacy VTK data block, ASCII or BINARY (big-endian), as doubles.
class VtkValues {
 public:
  VtkValues(std::istream& in, bool binary, const fs::path& path) : in_(in), binary_(binary), path_(path) {}

  // Call after the keyword line has been read up to its last token.
  std::vector<double> read(std::size_t count, const std::string& type, const std::string& what) {
    std::vector<double> out(count);
    if (!binary_) {
      for (auto& v : out) in_ >> v;
      if (!in_) fail(path_, what + ": expected " + std::to_string(count) + " values");
      return out;
    }
    in_.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
    const std::size_t size = type_size(type, what);
    std::vector<unsigned char> raw(count * size);
    in_.read(reinterpret_cast<char*>(raw.data()), static_cast<std::streamsize>(raw.size()));
    if (!in_) fail(path_, what + ": binary block truncated");
    for (std::size_t i = 0; i < count; ++i) {
      unsigned char b[8];
      for (std::size_t k = 0; k < size; ++k) b[k] = raw[i * size + size - 1 - k];  // big-endian
      out[i] = decode(b, type);
    }
    return out;
  }

 private:
  std::size_t type_size(const std::string& t, const std::string& what) const {
    if (t == "float" || t == "int" || t == "unsigned_int") return 4;
    if (t == "double" || t == "vtktypeint64" || t == "vtktypeuint64") return 8;
    if (t == "short" || t == "unsigned_short") return 2;
    if (t == "char" || t == "unsigned_char" || t == "bit") return 1;
    fail(path_, what + ": unsupported binary type '" + t + "'");
  }
  static double decode(const unsigned char* b, const std::string& t) {
    auto as = [&](auto v) {
      std::memcpy(&v, b, sizeof v);
      return static_cast<double>(v);
    };
    if (t == "float") return as(float{});
    if (t == "double") return as(double{});
    if (t == "int") return as(std::int32_t{});
    if (t == "unsigned_int") return as(std::uint32_t{});
    if (t == "vtktypeint64") return as(std::int64_t{});
    if (t == "vtktypeuint64") return as(std::uint64_t{});
    if (t == "short") return as(std::int16_t{});
    if (t == "unsigned_short") return as(std::uint16_t{});
    if (t == "char") return as(std::int8_t{});
    return as(std::uint8_t{});
  }
  std::istream& in_;
  bool binary_;
  const fs::path& path_;
};

}  // namespace

TriMesh read_vtk(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open the file");
  TriMesh mesh;
  mesh.name = body_name_of(path);
  std::string line;
  std::getline(in, line);
  if (line.rfind("# vtk DataFile", 0) != 0) fail(path, "missing '# vtk DataFile' header");
  std::getline(in, line);  // title
  std::string word, type;
  in >> word;
  if (word != "ASCII" && word != "BINARY") fail(path, "expected ASCII or BINARY (found '" + word + "')");
  VtkValues values(in, word == "BINARY", path);
  in >> word >> type;
  if (word != "DATASET" || type != "POLYDATA") fail(path, "expected 'DATASET POLYDATA'");
  std::vector<std::vector<std::int32_t>> polys;
  enum { kNone, kPoint, kCell } section = kNone;
  bool have_tissue = false, have_thickness = false, have_fibre = false;
  std::vector<double> tissue_codes, thickness, fibre;
  while (in >> word) {
    if (word == "POINTS") {
      std::size_t n;
      in >> n >> type;
      const auto xyz = values.read(3 * n, type, "POINTS");
      for (std::size_t i = 0; i < n; ++i) mesh.add_node(Vec3(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]));
    } else if (word == "POLYGONS" || word == "TRIANGLE_STRIPS" || word == "LINES" || word == "VERTICES") {
      std::size_t n, size;
      in >> n >> size;
      const auto flat = values.read(size, "int", word);
      std::size_t pos = 0;
      for (std::size_t i = 0; i < n; ++i) {
        if (pos >= flat.size()) fail(path, word + ": truncated");
        const auto k = static_cast<std::size_t>(flat[pos++]);
        if (pos + k > flat.size()) fail(path, word + ": truncated");
        std::vector<std::int32_t> ids(k);
        for (auto& id : ids) id = static_cast<std::int32_t>(flat[pos++]);
        if (word == "POLYGONS") polys.push_back(std::move(ids));
        else if (word == "TRIANGLE_STRIPS")
          for (std::size_t j = 2; j < ids.size(); ++j)
            polys.push_back(j % 2 ? std::vector<std::int32_t>{ids[j - 1], ids[j - 2], ids[j]}
                                  : std::vector<std::int32_t>{ids[j - 2], ids[j - 1], ids[j]});
      }
    } else if (word == "POINT_DATA" || word == "CELL_DATA") {
      std::size_t n;
      in >> n;
      section = word == "POINT_DATA" ? kPoint : kCell;
    } else if (word == "SCALARS" || word == "VECTORS" || word == "NORMALS") {
      std::string name;
      in >> name >> type;
      const bool vectors = word != "SCALARS";
      int components = vectors ? 3 : 1;
      if (!vectors) {
        std::getline(in, line);  // optional component count
        std::istringstream rest(line);
        if (!(rest >> components)) components = 1;
        std::string lt, table;
        in >> lt >> table;
        if (lt != "LOOKUP_TABLE") fail(path, "SCALARS " + name + ": expected LOOKUP_TABLE");
      }
      const std::size_t count = section == kPoint ? mesh.node_count() : polys.size();
      const auto data = values.read(count * components, type, name);
      if (section == kPoint && name == "region" && components == 1) {
        for (std::size_t i = 0; i < count; ++i) mesh.region[i] = static_cast<std::uint32_t>(data[i]);
      } else if (section == kCell && name == "tissue" && components == 1) {
        tissue_codes = data;
        have_tissue = true;
      } else if (section == kCell && name == "thickness_mm" && components == 1) {
        thickness = data;
        have_thickness = true;
      } else if (section == kCell && name == "fibre" && word == "VECTORS") {
        fibre = data;
        have_fibre = true;
      }
    } else if (word == "FIELD") {
      fail(path, "FIELD data is not supported; write fields as SCALARS / VECTORS");
    } else if (word == "METADATA" || word == "INFORMATION" || word == "NAME" || word == "DATA") {
      continue;  // ignored metadata keywords
    }
  }
  for (std::size_t p = 0; p < polys.size(); ++p) {
    const auto& ids = polys[p];
    for (auto id : ids)
      if (id < 0 || static_cast<std::size_t>(id) >= mesh.node_count()) fail(path, "polygon index out of range");
    if (ids.size() < 3) fail(path, "polygon with fewer than 3 points");
    if (ids.size() > 3 && (have_tissue || have_thickness || have_fibre))
      fail(path, "cell fields on non-triangular polygons are not supported");
    for (std::size_t k = 1; k + 1 < ids.size(); ++k) {
      if (have_tissue && (tissue_codes[p] < 0 || tissue_codes[p] >= kTissueCount))
        fail(path, "tissue code " + std::to_string(tissue_codes[p]) + " is unknown");
      const Tissue t = have_tissue ? static_cast<Tissue>(static_cast<int>(tissue_codes[p])) : Tissue::kLvMyocardium;
      mesh.add_triangle(ids[0], ids[k], ids[k + 1], t, have_thickness ? thickness[p] : 1.0,
                        have_fibre ? Vec3(fibre[3 * p], fibre[3 * p + 1], fibre[3 * p + 2]) : Vec3::Zero());
    }
  }
  if (mesh.tri.empty()) fail(path, "no polygons");
  return mesh;
}

TriMesh read_mesh(const fs::path& path) {
  std::string ext = path.extension().string();
  for (auto& ch : ext) ch = static_cast<char>(std::tolower(ch));
  if (ext == ".stl") return read_stl(path);
  if (ext == ".obj") return read_obj(path);
  if (ext == ".vtk") return read_vtk(path);
  throw InputError("cannot read mesh '" + path.string() + "': unknown extension '" + ext +
                   "'; known: .stl, .obj, .vtk");
}

void write_vtk(const fs::path& path, const TriMesh& mesh, bool binary) {
  std::ofstream f(path, std::ios::binary);
  if (!f) throw InputError("cannot write '" + path.string() + "'");
  char buf[96];
  auto put_be = [&](auto v) {  // one big-endian value
    unsigned char b[sizeof v];
    std::memcpy(b, &v, sizeof v);
    for (std::size_t k = 0; k < sizeof v; ++k) f.put(static_cast<char>(b[sizeof v - 1 - k]));
  };
  auto real = [&](double v) {
    if (binary) return put_be(v);
    std::snprintf(buf, sizeof buf, "%.17g", v);
    f << buf;
  };
  auto integer = [&](std::int64_t v, bool is_unsigned) {
    if (binary) return is_unsigned ? put_be(static_cast<std::uint32_t>(v)) : put_be(static_cast<std::int32_t>(v));
    f << v;
  };
  auto sep = [&](bool end_of_row) {
    if (!binary) f << (end_of_row ? '\n' : ' ');
  };
  auto end_block = [&]() {
    if (binary) f << '\n';
  };
  f << "# vtk DataFile Version 3.0\nsystole body " << mesh.name << " kind " << body_kind_name(mesh.kind) << "\n"
    << (binary ? "BINARY" : "ASCII") << "\nDATASET POLYDATA\n";
  f << "POINTS " << mesh.node_count() << " double\n";
  for (const auto& p : mesh.position_mm)
    for (int k = 0; k < 3; ++k) real(p[k]), sep(k == 2);
  end_block();
  f << "POLYGONS " << mesh.triangle_count() << " " << 4 * mesh.triangle_count() << "\n";
  for (const auto& t : mesh.tri) {
    integer(3, false), sep(false);
    for (int k = 0; k < 3; ++k) integer(t[k], false), sep(k == 2);
  }
  end_block();
  f << "POINT_DATA " << mesh.node_count() << "\nSCALARS region unsigned_int 1\nLOOKUP_TABLE default\n";
  for (auto r : mesh.region) integer(r, true), sep(true);
  end_block();
  f << "CELL_DATA " << mesh.triangle_count() << "\nSCALARS tissue int 1\nLOOKUP_TABLE default\n";
  for (auto t : mesh.tissue) integer(static_cast<int>(t), false), sep(true);
  end_block();
  f << "SCALARS thickness_mm double 1\nLOOKUP_TABLE default\n";
  for (auto t : mesh.thickness_mm) real(t), sep(true);
  end_block();
  f << "VECTORS fibre double\n";
  for (const auto& v : mesh.fibre)
    for (int k = 0; k < 3; ++k) real(v[k]), sep(k == 2);
  end_block();
  if (!f) throw InputError("cannot write '" + path.string() + "'");
}

void write_stl_binary(const fs::path& path, const TriMesh& mesh) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw InputError("cannot write '" + path.string() + "'");
  char header[80] = {};
  std::snprintf(header, sizeof header, "systole body %s", mesh.name.c_str());
  out.write(header, 80);
  const auto n = static_cast<std::uint32_t>(mesh.triangle_count());
  out.write(reinterpret_cast<const char*>(&n), 4);
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    float rec[12];
    const Vec3 nrm = mesh.unit_normal(t);
    for (int k = 0; k < 3; ++k) rec[k] = static_cast<float>(nrm[k]);
    for (int v = 0; v < 3; ++v)
      for (int k = 0; k < 3; ++k) rec[3 + 3 * v + k] = static_cast<float>(mesh.position_mm[mesh.tri[t][v]][k]);
    out.write(reinterpret_cast<const char*>(rec), 48);
    const std::uint16_t attr = 0;
    out.write(reinterpret_cast<const char*>(&attr), 2);
  }
}

void write_obj(const fs::path& path, const TriMesh& mesh) {
  std::FILE* f = std::fopen(path.string().c_str(), "w");
  if (!f) throw InputError("cannot write '" + path.string() + "'");
  std::fprintf(f, "# systole body %s\n", mesh.name.c_str());
  for (const auto& p : mesh.position_mm) std::fprintf(f, "v %.17g %.17g %.17g\n", p.x(), p.y(), p.z());
  for (const auto& t : mesh.tri) std::fprintf(f, "f %d %d %d\n", t[0] + 1, t[1] + 1, t[2] + 1);
  std::fclose(f);
}

// ---- XDMF + HDF5 ------------------------------------------------------------------------------
namespace {

void h5_check(herr_t status, const std::string& what) {
  if (status < 0) throw InputError("HDF5: " + what + " failed");
}

template <class T>
void h5_write(hid_t group, const char* name, hid_t type, const std::vector<T>& data, hsize_t rows,
              hsize_t cols) {
  const hsize_t dims[2] = {rows, cols};
  const hid_t space = H5Screate_simple(cols == 1 ? 1 : 2, dims, nullptr);
  const hid_t set = H5Dcreate2(group, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (set < 0) throw InputError(std::string("HDF5: cannot create dataset ") + name);
  if (rows) h5_check(H5Dwrite(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()), name);
  H5Dclose(set);
  H5Sclose(space);
}

template <class T>
std::vector<T> h5_read(hid_t group, const char* name, hid_t type, hsize_t& rows) {
  const hid_t set = H5Dopen2(group, name, H5P_DEFAULT);
  if (set < 0) throw InputError(std::string("HDF5: no dataset ") + name);
  const hid_t space = H5Dget_space(set);
  hsize_t dims[2] = {0, 1};
  const int nd = H5Sget_simple_extent_dims(space, dims, nullptr);
  rows = dims[0];
  std::vector<T> data(dims[0] * (nd == 2 ? dims[1] : 1));
  if (!data.empty()) h5_check(H5Dread(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()), name);
  H5Sclose(space);
  H5Dclose(set);
  return data;
}

}  // namespace

std::vector<fs::path> write_xdmf_hdf5(const fs::path& base, const std::vector<const TriMesh*>& bodies) {
  const fs::path h5 = fs::path(base).replace_extension(".h5");
  const fs::path xmf = fs::path(base).replace_extension(".xdmf");
  const hid_t file = H5Fcreate(h5.string().c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (file < 0) throw InputError("cannot create '" + h5.string() + "'");
  std::ostringstream x;
  x << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n"
    << "  <Grid Name=\"heart\" GridType=\"Collection\" CollectionType=\"Spatial\">\n";
  const std::string h5name = h5.filename().string();
  for (const TriMesh* const& m : bodies) {
    const hid_t g = H5Gcreate2(file, m->name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (g < 0) throw InputError("HDF5: cannot create group '" + m->name + "' (duplicate body name?)");
    const std::size_t n = m->node_count(), t = m->triangle_count();
    std::vector<double> pos(3 * n), fib(3 * t);
    for (std::size_t i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) pos[3 * i + k] = m->position_mm[i][k];
    std::vector<std::int32_t> tri(3 * t), tissue(t);
    for (std::size_t i = 0; i < t; ++i) {
      for (int k = 0; k < 3; ++k) {
        tri[3 * i + k] = m->tri[i][k];
        fib[3 * i + k] = m->fibre[i][k];
      }
      tissue[i] = static_cast<std::int32_t>(m->tissue[i]);
    }
    h5_write(g, "points_mm", H5T_NATIVE_DOUBLE, pos, n, 3);
    h5_write(g, "triangles", H5T_NATIVE_INT32, tri, t, 3);
    h5_write(g, "region", H5T_NATIVE_UINT32, m->region, n, 1);
    h5_write(g, "tissue", H5T_NATIVE_INT32, tissue, t, 1);
    h5_write(g, "thickness_mm", H5T_NATIVE_DOUBLE, m->thickness_mm, t, 1);
    h5_write(g, "fibre", H5T_NATIVE_DOUBLE, fib, t, 3);
    const int attrs[2] = {static_cast<int>(m->kind), static_cast<int>(&m - &bodies[0])};
    const char* attr_names[2] = {"kind", "index"};
    for (int k = 0; k < 2; ++k) {
      const hid_t as = H5Screate(H5S_SCALAR);
      const hid_t attr = H5Acreate2(g, attr_names[k], H5T_NATIVE_INT, as, H5P_DEFAULT, H5P_DEFAULT);
      H5Awrite(attr, H5T_NATIVE_INT, &attrs[k]);
      H5Aclose(attr);
      H5Sclose(as);
    }
    H5Gclose(g);
    const std::string p = h5name + ":/" + m->name + "/";
    x << "   <Grid Name=\"" << m->name << "\" GridType=\"Uniform\">\n"
      << "    <Topology TopologyType=\"Triangle\" NumberOfElements=\"" << t << "\">\n"
      << "     <DataItem Dimensions=\"" << t << " 3\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">" << p
      << "triangles</DataItem>\n    </Topology>\n"
      << "    <Geometry GeometryType=\"XYZ\">\n     <DataItem Dimensions=\"" << n
      << " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << p << "points_mm</DataItem>\n    </Geometry>\n"
      << "    <Attribute Name=\"region\" AttributeType=\"Scalar\" Center=\"Node\">\n     <DataItem Dimensions=\"" << n
      << "\" NumberType=\"UInt\" Precision=\"4\" Format=\"HDF\">" << p << "region</DataItem>\n    </Attribute>\n"
      << "    <Attribute Name=\"tissue\" AttributeType=\"Scalar\" Center=\"Cell\">\n     <DataItem Dimensions=\"" << t
      << "\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">" << p << "tissue</DataItem>\n    </Attribute>\n"
      << "    <Attribute Name=\"thickness_mm\" AttributeType=\"Scalar\" Center=\"Cell\">\n     <DataItem Dimensions=\""
      << t << "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << p
      << "thickness_mm</DataItem>\n    </Attribute>\n"
      << "    <Attribute Name=\"fibre\" AttributeType=\"Vector\" Center=\"Cell\">\n     <DataItem Dimensions=\"" << t
      << " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << p << "fibre</DataItem>\n    </Attribute>\n"
      << "   </Grid>\n";
  }
  x << "  </Grid>\n </Domain>\n</Xdmf>\n";
  H5Fclose(file);
  std::ofstream out(xmf);
  out << x.str();
  if (!out) throw InputError("cannot write '" + xmf.string() + "'");
  return {h5, xmf};
}

std::vector<TriMesh> read_hdf5(const fs::path& h5_path) {
  const hid_t file = H5Fopen(h5_path.string().c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) throw InputError("cannot open '" + h5_path.string() + "'");
  std::vector<std::string> names;
  H5Literate(
      file, H5_INDEX_NAME, H5_ITER_INC, nullptr,
      [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
        static_cast<std::vector<std::string>*>(data)->push_back(name);
        return 0;
      },
      &names);
  std::vector<TriMesh> out;
  std::vector<int> order;
  for (const auto& name : names) {
    const hid_t g = H5Gopen2(file, name.c_str(), H5P_DEFAULT);
    TriMesh m;
    m.name = name;
    hsize_t n, t, dummy;
    const auto pos = h5_read<double>(g, "points_mm", H5T_NATIVE_DOUBLE, n);
    const auto tri = h5_read<std::int32_t>(g, "triangles", H5T_NATIVE_INT32, t);
    m.region = h5_read<std::uint32_t>(g, "region", H5T_NATIVE_UINT32, dummy);
    const auto tissue = h5_read<std::int32_t>(g, "tissue", H5T_NATIVE_INT32, dummy);
    m.thickness_mm = h5_read<double>(g, "thickness_mm", H5T_NATIVE_DOUBLE, dummy);
    const auto fib = h5_read<double>(g, "fibre", H5T_NATIVE_DOUBLE, dummy);
    int kind = 0, index = 0;
    for (auto [attr_name, value] : {std::pair{"kind", &kind}, std::pair{"index", &index}}) {
      const hid_t attr = H5Aopen(g, attr_name, H5P_DEFAULT);
      if (attr < 0) throw InputError("'" + h5_path.string() + "': group '" + name + "' lacks attribute " + attr_name);
      H5Aread(attr, H5T_NATIVE_INT, value);
      H5Aclose(attr);
    }
    order.push_back(index);
    m.kind = static_cast<BodyKind>(kind);
    for (hsize_t i = 0; i < n; ++i) m.position_mm.emplace_back(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]);
    for (hsize_t i = 0; i < t; ++i) {
      m.tri.push_back({tri[3 * i], tri[3 * i + 1], tri[3 * i + 2]});
      m.tissue.push_back(static_cast<Tissue>(tissue[i]));
      m.fibre.emplace_back(fib[3 * i], fib[3 * i + 1], fib[3 * i + 2]);
    }
    H5Gclose(g);
    m.check_arrays();
    out.push_back(std::move(m));
  }
  H5Fclose(file);
  std::vector<TriMesh> sorted(out.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (order[i] < 0 || static_cast<std::size_t>(order[i]) >= out.size())
      throw InputError("'" + h5_path.string() + "': bad body index attribute");
    sorted[order[i]] = std::move(out[i]);
  }
  return sorted;
}

// ---- manifest -----------------------------------------------------------------------------------
namespace {

Vec3 vec3_of(const nlohmann::json& j, const std::string& where) {
  if (!j.is_array() || j.size() != 3) throw InputError(where + " must be an array of 3 numbers");
  return Vec3(j[0].get<double>(), j[1].get<double>(), j[2].get<double>());
}

void apply_fibre_rule(TriMesh& m, const nlohmann::json& rule, const std::string& where) {
  const std::string name = rule.value("rule", "keep");
  const Vec3 axis = rule.contains("axis") ? vec3_of(rule["axis"], where + ".axis").normalized() : Vec3::UnitZ();
  const Vec3 origin = rule.contains("axis_point_mm") ? vec3_of(rule["axis_point_mm"], where + ".axis_point_mm")
                                                     : Vec3::Zero();
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const Vec3 c = m.centroid(t), n = m.unit_normal(t);
    const Vec3 radial = (c - origin) - (c - origin).dot(axis) * axis;
    const Vec3 circ = tangent_in_triangle(m, t, axis.cross(radial), Vec3::UnitX());
    if (name == "keep") {
      if (m.fibre[t].norm() == 0)
        throw InputError(where + ": rule 'keep' but the file has no fibres; use helix, vertical, "
                         "circumferential or constant");
      m.fibre[t] = tangent_in_triangle(m, t, m.fibre[t], Vec3::UnitX());
    } else if (name == "helix") {
      const double alpha = rule.value("angle_deg", 45.0) * M_PI / 180;
      Vec3 up = n.cross(circ);
      if (up.dot(axis) > 0) up = -up;
      m.fibre[t] = (std::cos(alpha) * circ + std::sin(alpha) * up).normalized();
    } else if (name == "vertical") {
      m.fibre[t] = tangent_in_triangle(m, t, -axis, circ);
    } else if (name == "circumferential") {
      m.fibre[t] = circ;
    } else if (name == "constant") {
      m.fibre[t] = tangent_in_triangle(m, t, vec3_of(rule.at("direction"), where + ".direction"), circ);
    } else {
      throw InputError(where + ".rule = '" + name + "' is unknown; known: keep, helix, vertical, circumferential, constant");
    }
  }
}

}  // namespace

ImportedHeart load_manifest(const fs::path& manifest_path) {
  std::ifstream in(manifest_path);
  if (!in) throw InputError("cannot open manifest '" + manifest_path.string() + "'");
  nlohmann::json doc;
  try {
    in >> doc;
  } catch (const nlohmann::json::exception& e) {
    throw InputError("manifest '" + manifest_path.string() + "' is not valid JSON: " + e.what());
  }
  ImportedHeart heart;
  const std::string mf = "manifest '" + manifest_path.string() + "'";
  try {
    heart.plane_z_mm = doc.at("valvular_plane_z_mm").get<double>();
    const auto& bodies = doc.at("bodies");
    for (std::size_t b = 0; b < bodies.size(); ++b) {
      const auto& e = bodies[b];
      const std::string where = mf + " bodies[" + std::to_string(b) + "]";
      fs::path file = e.at("file").get<std::string>();
      if (file.is_relative()) file = manifest_path.parent_path() / file;
      TriMesh m = read_mesh(file);
      m.name = e.value("name", m.name);
      m.kind = body_kind_from_name(e.value("kind", std::string("chamber")));
      const double scale = e.value("scale_to_mm", 1.0);
      for (auto& p : m.position_mm) p *= scale;
      if (e.value("flip_normals", false)) m.flip_orientation();
      const bool has_fields = file.extension() == ".vtk" && !m.fibre.empty() && m.fibre[0].norm() > 0;
      if (e.contains("tissue")) {
        const Tissue t = tissue_from_name(e["tissue"].get<std::string>());
        std::fill(m.tissue.begin(), m.tissue.end(), t);
      } else if (!has_fields) {
        throw InputError(where + ": 'tissue' is required (known: valvular_plane, lv_myocardium, ...)");
      }
      if (e.contains("thickness_mm")) {
        const double th = e["thickness_mm"].get<double>();
        if (!(th > 0)) throw InputError(where + ".thickness_mm = " + std::to_string(th) + " must be > 0");
        std::fill(m.thickness_mm.begin(), m.thickness_mm.end(), th);
      } else if (!has_fields) {
        throw InputError(where + ": 'thickness_mm' is required");
      }
      apply_fibre_rule(m, e.value("fibre", nlohmann::json{{"rule", has_fields ? "keep" : "constant"},
                                                          {"direction", {1, 0, 0}}}),
                       where + ".fibre");
      for (const auto& r : e.value("regions", nlohmann::json::array())) {
        const Region bit = region_from_name(r.at("name").get<std::string>());
        if (r.contains("near_plane_mm")) {
          const double tol = r["near_plane_mm"].get<double>();
          for (std::size_t i = 0; i < m.node_count(); ++i)
            if (std::abs(m.position_mm[i].z() - heart.plane_z_mm) <= tol) m.region[i] |= bit;
        } else if (r.contains("sphere")) {
          const Vec3 c = vec3_of(r["sphere"].at("centre_mm"), where + " region sphere centre_mm");
          const double rad = r["sphere"].at("radius_mm").get<double>();
          for (std::size_t i = 0; i < m.node_count(); ++i)
            if ((m.position_mm[i] - c).norm() <= rad) m.region[i] |= bit;
        } else if (r.contains("nodes")) {
          for (const auto& id : r["nodes"]) {
            const auto i = id.get<long>();
            if (i < 0 || static_cast<std::size_t>(i) >= m.node_count())
              throw InputError(where + " region '" + r["name"].get<std::string>() + "': node " + std::to_string(i) +
                               " out of range [0, " + std::to_string(m.node_count()) + ")");
            m.region[i] |= bit;
          }
        } else {
          throw InputError(where + " region '" + r["name"].get<std::string>() +
                           "': give one of near_plane_mm, sphere, nodes");
        }
      }
      heart.bodies.push_back(std::move(m));
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(mf + ": " + e.what());
  }
  return heart;
}

}  // namespace systole::geometry
