#include "planner_plugin/io/fem_dataset_h5.h"

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <system_error>
#include <utility>

#include "shape/core/error.h"

namespace pectus::planner {
namespace {

// Checks an HDF5 return value; throws naming the file and what was being written.
hid_t Check(hid_t id, const std::filesystem::path& path, const std::string& what) {
  if (id < 0) ThrowFailure("HDF5 could not write " + what, path.string());
  return id;
}

void WriteDataset(hid_t parent, const std::string& name, hid_t file_type, hid_t memory_type,
                  const std::vector<hsize_t>& dims, const void* data, const std::filesystem::path& path,
                  bool compress = false) {
  const hid_t space =
      Check(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), path, name);
  const hid_t properties = H5Pcreate(H5P_DATASET_CREATE);
  H5Pset_obj_track_times(properties, false);  // no modification times: the same data, the same bytes
  if (compress) {
    std::vector<hsize_t> chunk = dims;
    chunk[0] = 1;  // one load case per chunk
    H5Pset_chunk(properties, static_cast<int>(chunk.size()), chunk.data());
    H5Pset_shuffle(properties);
    H5Pset_deflate(properties, 4);
  }
  const hid_t set = Check(
      H5Dcreate2(parent, name.c_str(), file_type, space, H5P_DEFAULT, properties, H5P_DEFAULT), path, name);
  Check(H5Dwrite(set, memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), path, name);
  H5Dclose(set);
  H5Pclose(properties);
  H5Sclose(space);
}

void WriteAttribute(hid_t object, const std::string& name, double value, const std::filesystem::path& path) {
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t attribute =
      Check(H5Acreate2(object, name.c_str(), H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT), path, name);
  H5Awrite(attribute, H5T_NATIVE_DOUBLE, &value);
  H5Aclose(attribute);
  H5Sclose(space);
}

void WriteAttribute(hid_t object, const std::string& name, const std::string& value,
                    const std::filesystem::path& path) {
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, std::max<std::size_t>(1, value.size()));
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t attribute =
      Check(H5Acreate2(object, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT), path, name);
  H5Awrite(attribute, type, value.c_str());
  H5Aclose(attribute);
  H5Sclose(space);
  H5Tclose(type);
}

hid_t Group(hid_t parent, const std::string& name, const std::filesystem::path& path) {
  const hid_t properties = H5Pcreate(H5P_GROUP_CREATE);
  H5Pset_obj_track_times(properties, false);
  const hid_t group = H5Gcreate2(parent, name.c_str(), H5P_DEFAULT, properties, H5P_DEFAULT);
  H5Pclose(properties);
  return Check(group, path, name);
}

// Creates `path` (truncating) so that the same objects written in the same order give the same bytes: no
// object modification times, and a fixed range of HDF5 file format versions (not the library's newest).
hid_t CreateReproducibleFile(const std::filesystem::path& path, const std::filesystem::path& named) {
  const hid_t creation = H5Pcreate(H5P_FILE_CREATE), access = H5Pcreate(H5P_FILE_ACCESS);
  H5Pset_obj_track_times(creation, false);  // the root group's
  H5Pset_libver_bounds(access, H5F_LIBVER_V18, H5F_LIBVER_V18);
  const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, creation, access);
  H5Pclose(creation);
  H5Pclose(access);
  return Check(file, named, "the file");
}

}  // namespace

struct FemDatasetWriter::File {
  hid_t id = -1;
  hid_t patients = -1;
  ~File() {
    if (patients >= 0) H5Gclose(patients);
    if (id >= 0) H5Fclose(id);
  }
};

FemDatasetWriter::FemDatasetWriter(const std::filesystem::path& path, const GenericRibcage& generic,
                                   std::vector<BarLoad> loads, const RibcageMaterials& materials)
    : file_(std::make_unique<File>()), path_(path), loads_(std::move(loads)) {
  temp_ = output_.Stage(path_);  // HDF5 writes to a file name: staged, renamed into place by Commit()
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are reported through pectus::Error
  file_->id = CreateReproducibleFile(temp_, path_);
  const hid_t root = file_->id;
  WriteAttribute(
      root, "description",
      "pectus planner finite element dataset: surface-node displacements of patient-specific ribcages "
      "(Rechowicz 2012, section 4.1.2) under the Nuss bar's push",
      path_);
  WriteAttribute(root, "units", "mm, N, MPa", path_);
  WriteAttribute(root, "frame", "LPS (x left, y posterior, z superior), origin at the sternal notch", path_);
  WriteAttribute(root, "load_case_order", "as /load_cases: bar position major, force minor", path_);
  std::string listed;
  for (const IsotropicMaterial* m : {&materials.sternum, &materials.rib, &materials.cartilage}) {
    char text[96];
    std::snprintf(text, sizeof(text), "%s%s E %g MPa nu %g", listed.empty() ? "" : ", ", m->name.c_str(),
                  m->youngs_modulus_mpa, m->poisson_ratio);
    listed += text;
  }
  WriteAttribute(root, "materials", listed, path_);
  WriteAttribute(root, "cartilage_youngs_modulus_mpa", materials.cartilage.youngs_modulus_mpa, path_);
  // Load cases.
  std::vector<double> position, force;
  for (const BarLoad& l : loads_) {
    if (l.position_in_mm) ThrowUsage("FE dataset: bar positions must be fractions of the sternal length");
    position.push_back(l.position);
    force.push_back(l.force_n);
  }
  const hid_t cases = Group(root, "load_cases", path_);
  WriteDataset(cases, "position", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {loads_.size()}, position.data(), path_);
  WriteDataset(cases, "force_n", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {loads_.size()}, force.data(), path_);
  H5Gclose(cases);
  // Topology: the bone surface over its corner nodes.
  Eigen::VectorXi face_tet;
  const Faces3 faces = ExtractLinearBoundary(generic.tets, &face_tet);
  std::vector<std::int32_t> index(static_cast<std::size_t>(generic.nodes.rows()), -1);
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    for (int i = 0; i < 3; ++i) index[faces(f, i)] = 0;
  }
  for (std::size_t i = 0; i < index.size(); ++i) {
    if (index[i] == 0) {
      index[i] = static_cast<std::int32_t>(surface_nodes_.size());
      surface_nodes_.push_back(static_cast<std::int32_t>(i));
    }
  }
  std::vector<std::int32_t> tri, region, part;
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    for (int i = 0; i < 3; ++i) tri.push_back(index[faces(f, i)]);
    region.push_back(generic.regions(face_tet(f)));
    part.push_back(generic.tet_parts(face_tet(f)));
  }
  const hid_t topology = Group(root, "topology", path_);
  const hsize_t nf = static_cast<hsize_t>(faces.rows());
  WriteDataset(topology, "faces", H5T_STD_I32LE, H5T_NATIVE_INT32, {nf, 3}, tri.data(), path_);
  WriteDataset(topology, "face_region", H5T_STD_I32LE, H5T_NATIVE_INT32, {nf}, region.data(), path_);
  WriteDataset(topology, "face_part", H5T_STD_I32LE, H5T_NATIVE_INT32, {nf}, part.data(), path_);
  H5Gclose(topology);
  file_->patients = Group(root, "patients", path_);
}

FemDatasetWriter::~FemDatasetWriter() {
  file_.reset();  // closed before output_ removes the staged file of an uncommitted dataset
}

double RestChecksum(const Eigen::VectorXd& rest_positions) {
  double sum = 0.0;
  for (Eigen::Index i = 0; i < rest_positions.size(); ++i)
    sum += rest_positions[i] * static_cast<double>(1 + i % 7);
  return sum;
}

namespace {

constexpr const char* kBasisScalars =
    "num_points, contact_width_mm, notch_z_mm, sternal_length_mm, truncation_bound_mm_per_n, bone_vertices, "
    "skin_vertices, skin_landmarks, mesh_nodes, rest_checksum_mm";

void WriteResponseBasis(hid_t patient, const StoredResponseBasis& b, const std::filesystem::path& path) {
  const BarResponseBasis::Stored& s = b.arrays;
  const hid_t group = Group(patient, "response_basis", path);
  WriteAttribute(group, "scalars_order", kBasisScalars, path);
  const double scalars[10] = {static_cast<double>(s.num_points),
                              s.contact_width_mm,
                              s.notch_z_mm,
                              s.sternal_length_mm,
                              s.truncation_bound_mm_per_n,
                              static_cast<double>(b.bone_vertices),
                              static_cast<double>(b.skin_vertices),
                              static_cast<double>(b.skin_landmarks),
                              static_cast<double>(b.mesh_nodes),
                              b.rest_checksum_mm};
  WriteDataset(group, "scalars", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {10}, scalars, path);
  using RowMajorF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  using RowMajorD = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  using RowMajorI = Eigen::Matrix<std::int32_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const RowMajorF modes = s.modes;
  const RowMajorD mixing = s.mixing, N = s.quadrature_N;
  const RowMajorI contact = s.quadrature_contact;
  const auto dims = [](Eigen::Index rows, Eigen::Index cols) {
    return std::vector<hsize_t>{static_cast<hsize_t>(rows), static_cast<hsize_t>(cols)};
  };
  WriteDataset(group, "modes", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, dims(modes.rows(), modes.cols()),
               modes.data(), path);
  WriteDataset(group, "mixing", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, dims(mixing.rows(), mixing.cols()),
               mixing.data(), path);
  WriteDataset(group, "lift", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {static_cast<hsize_t>(s.lift.size())},
               s.lift.data(), path);
  WriteDataset(group, "contact_nodes", H5T_STD_I32LE, H5T_NATIVE_INT32, {s.contact_nodes.size()},
               s.contact_nodes.data(), path);
  const auto Q = static_cast<hsize_t>(s.quadrature_z.size());
  WriteDataset(group, "quadrature_z", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {Q}, s.quadrature_z.data(), path);
  WriteDataset(group, "quadrature_weight", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {Q}, s.quadrature_weight.data(),
               path);
  WriteDataset(group, "quadrature_contact", H5T_STD_I32LE, H5T_NATIVE_INT32, {Q, 6}, contact.data(), path);
  WriteDataset(group, "quadrature_N", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {Q, 6}, N.data(), path);
  WriteDataset(group, "singular_values", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE,
               {static_cast<hsize_t>(s.singular_values.size())}, s.singular_values.data(), path);
  H5Gclose(group);
}

}  // namespace

void FemDatasetWriter::AddPatient(const PatientRibcage& ribcage, const std::vector<BarResult>& results,
                                  const std::vector<ForceToLift>& force_to_lift, double ct_haller_index,
                                  const StoredResponseBasis* basis) {
  if (results.size() != loads_.size()) {
    ThrowFailure("FE dataset: patient " + ribcage.patient + " has " + std::to_string(results.size()) +
                 " results for " + std::to_string(loads_.size()) + " load cases");
  }
  const hid_t group = Group(file_->patients, ribcage.patient, path_);
  const std::size_t n = surface_nodes_.size();
  std::vector<double> nodes(n * 3);
  std::vector<float> displacement(results.size() * n * 3);
  std::vector<double> lift;
  for (std::size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) nodes[3 * i + c] = ribcage.mesh.nodes(surface_nodes_[i], c);
  }
  for (std::size_t k = 0; k < results.size(); ++k) {
    for (std::size_t i = 0; i < n; ++i) {
      for (int c = 0; c < 3; ++c) {
        displacement[(k * n + i) * 3 + c] = static_cast<float>(results[k].displacement(surface_nodes_[i], c));
      }
    }
    lift.push_back(results[k].sternum_lift_mm);
  }
  WriteDataset(group, "nodes", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {n, 3}, nodes.data(), path_);
  WriteDataset(group, "displacements", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {results.size(), n, 3},
               displacement.data(), path_, true);
  WriteDataset(group, "sternum_lift", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {lift.size()}, lift.data(), path_);
  const PatientMeasurements& t = ribcage.targets;
  const RibcageMeasurements& m = ribcage.measured;
  WriteAttribute(group, "ct_width_mm", t.TrueWidth(), path_);
  WriteAttribute(group, "ct_depth_mm", t.TrueDepth(), path_);
  WriteAttribute(group, "ct_sternal_length_mm", t.SternalLength(), path_);
  WriteAttribute(group, "ct_depression_mm", t.TrueDepression(), path_);
  WriteAttribute(group, "ct_haller_index", ct_haller_index, path_);
  WriteAttribute(group, "model_width_mm", m.width_mm, path_);
  WriteAttribute(group, "model_depth_mm", m.depth_mm, path_);
  WriteAttribute(group, "model_sternal_length_mm", m.sternal_length_mm, path_);
  WriteAttribute(group, "model_depression_mm", m.depression_mm, path_);
  WriteAttribute(group, "model_haller_index", m.haller_index, path_);
  WriteAttribute(group, "map_scale_x", ribcage.parameters.scale.x(), path_);
  WriteAttribute(group, "map_scale_y", ribcage.parameters.scale.y(), path_);
  WriteAttribute(group, "map_scale_z", ribcage.parameters.scale.z(), path_);
  WriteAttribute(group, "map_sternal_displacement_mm", ribcage.parameters.depression_mm, path_);
  for (const ForceToLift& f : force_to_lift) {
    char name[64];
    std::snprintf(name, sizeof(name), "force_to_lift_n_at_%.2f", f.position.position);
    WriteAttribute(group, name, f.force_n, path_);
  }
  if (basis != nullptr) WriteResponseBasis(group, *basis, path_);
  H5Gclose(group);
}

void FemDatasetWriter::Commit() {
  file_.reset();
  output_.CommitAll();
}

// ---- reading ----

namespace {

// Reads datasets of one open file, every failure an Error(kBadInput) naming the file and the dataset.
class Reader {
 public:
  Reader(hid_t file, std::string name) : file_(file), name_(std::move(name)) {}
  ~Reader() {
    if (file_ >= 0) H5Fclose(file_);
  }
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  [[noreturn]] void Bad(const std::string& what) const { ThrowBadInput(name_, what); }

  // The numbers of dataset `path` as doubles, checked to have shape `dims` (0: any extent) and to be
  // finite; `*shape` gets the dataset's shape.
  std::vector<double> Numbers(const std::string& path, const std::vector<hsize_t>& dims,
                              std::vector<hsize_t>* shape = nullptr) const {
    if (H5Lexists(file_, path.c_str(), H5P_DEFAULT) <= 0) Bad("has no dataset /" + path);
    const hid_t set = H5Dopen2(file_, path.c_str(), H5P_DEFAULT);
    if (set < 0) Bad("/" + path + " is not a dataset");
    std::vector<double> values;
    std::string error;
    const hid_t space = H5Dget_space(set), type = H5Dget_type(set);
    const int rank = space < 0 ? -1 : H5Sget_simple_extent_ndims(space);
    std::vector<hsize_t> extent(static_cast<std::size_t>(std::max(rank, 0)));
    if (rank >= 0) H5Sget_simple_extent_dims(space, extent.data(), nullptr);
    hsize_t count = 1;
    for (hsize_t d : extent)
      count = d == 0 || count <= (hsize_t{1} << 31) / d ? count * d : (hsize_t{1} << 32);
    if (rank < 0 || type < 0) {
      error = "/" + path + " cannot be read";
    } else if (H5Tget_class(type) != H5T_FLOAT && H5Tget_class(type) != H5T_INTEGER) {
      error = "/" + path + " is not numeric";
    } else if (extent.size() != dims.size()) {
      error = "/" + path + " has " + std::to_string(rank) + " dimensions, expected " +
              std::to_string(dims.size());
    } else if (count > (hsize_t{1} << 31)) {
      error = "/" + path + " is too large (over 2^31 numbers)";
    } else if (count > 0 && H5Dget_storage_size(set) == 0) {
      error = "/" + path + " holds no data";
    } else {
      for (std::size_t i = 0; i < dims.size() && error.empty(); ++i) {
        if (dims[i] != 0 && extent[i] != dims[i]) {
          error = "/" + path + " has extent " + std::to_string(extent[i]) + " in dimension " +
                  std::to_string(i + 1) + ", expected " + std::to_string(dims[i]);
        }
      }
      values.resize(static_cast<std::size_t>(count));
      if (error.empty() && count > 0 &&
          H5Dread(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()) < 0) {
        error = "/" + path + " cannot be read";
      }
    }
    if (type >= 0) H5Tclose(type);
    if (space >= 0) H5Sclose(space);
    H5Dclose(set);
    if (!error.empty()) Bad(error);
    for (double v : values) {
      if (!std::isfinite(v)) Bad("/" + path + " holds a non-finite number");
    }
    if (shape != nullptr) *shape = extent;
    return values;
  }

  // Whether `path` names something in the file (each of its parents checked first).
  bool Exists(const std::string& path) const {
    std::size_t at = 0;
    while ((at = path.find('/', at + 1)) != std::string::npos) {
      if (H5Lexists(file_, path.substr(0, at).c_str(), H5P_DEFAULT) <= 0) return false;
    }
    return H5Lexists(file_, path.c_str(), H5P_DEFAULT) > 0;
  }
  const std::string& name() const { return name_; }

  // The names of the members of group `path`.
  std::vector<std::string> Members(const std::string& path) const {
    if (H5Lexists(file_, path.c_str(), H5P_DEFAULT) <= 0) Bad("has no group /" + path);
    H5O_info_t info;
    if (H5Oget_info_by_name(file_, path.c_str(), &info, H5P_DEFAULT) < 0 || info.type != H5O_TYPE_GROUP)
      Bad("/" + path + " is not a group");
    std::vector<std::string> names;
    const auto add = [](hid_t, const char* member, const H5L_info_t*, void* out) -> herr_t {
      static_cast<std::vector<std::string>*>(out)->emplace_back(member);
      return 0;
    };
    if (H5Literate_by_name(file_, path.c_str(), H5_INDEX_NAME, H5_ITER_INC, nullptr, add, &names,
                           H5P_DEFAULT) < 0) {
      Bad("cannot list /" + path);
    }
    return names;
  }

 private:
  hid_t file_;
  std::string name_;
};

// Whole numbers of a dataset as int32 (indices), each checked.
template <typename Out>
void WholeNumbers(const Reader& r, const std::vector<double>& values, const std::string& path, Out* out) {
  for (std::size_t i = 0; i < values.size(); ++i) {
    const double v = values[i];
    if (v != std::floor(v) || std::abs(v) > 2e9)
      r.Bad("/" + path + " holds " + std::to_string(v) + ", not an index");
    (*out)[static_cast<Eigen::Index>(i)] = static_cast<std::int32_t>(v);
  }
}

// The response basis of patient group `group` ("patients/<id>/"), checked (BarResponseBasis's own
// checks run on it too, by whoever makes the basis).
StoredResponseBasis ReadResponseBasis(const Reader& r, const std::string& group, const std::string& source) {
  const std::string g = group + "response_basis/";
  StoredResponseBasis b;
  BarResponseBasis::Stored& s = b.arrays;
  const std::vector<double> scalars = r.Numbers(g + "scalars", {10});
  for (int i : {0, 5, 6, 7, 8}) {
    if (scalars[i] != std::floor(scalars[i]) || scalars[i] < 0 || scalars[i] > 1e9)
      r.Bad("/" + g + "scalars holds a count that is not a whole number: " + std::to_string(scalars[i]));
  }
  s.num_points = static_cast<Eigen::Index>(scalars[0]);
  s.contact_width_mm = scalars[1];
  s.notch_z_mm = scalars[2];
  s.sternal_length_mm = scalars[3];
  s.truncation_bound_mm_per_n = scalars[4];
  b.bone_vertices = static_cast<std::int64_t>(scalars[5]);
  b.skin_vertices = static_cast<std::int64_t>(scalars[6]);
  b.skin_landmarks = static_cast<std::int64_t>(scalars[7]);
  b.mesh_nodes = static_cast<std::int64_t>(scalars[8]);
  b.rest_checksum_mm = scalars[9];
  if (b.bone_vertices + b.skin_vertices + b.skin_landmarks != s.num_points || s.num_points == 0)
    r.Bad("/" + g + "scalars: bone, skin and landmark points do not add up to num_points (> 0)");
  // Every extent read below must be positive: an expected extent of 0 would mean "any" to Numbers().
  auto positive = [&](hsize_t extent, const std::string& what) {
    if (extent == 0) r.Bad("/" + g + what + " is empty");
    return extent;
  };
  std::vector<hsize_t> shape;
  const std::vector<double> modes =
      r.Numbers(g + "modes", {static_cast<hsize_t>(3 * s.num_points), 0}, &shape);
  const auto rank = static_cast<Eigen::Index>(positive(shape[1], "modes"));
  s.modes = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
                modes.data(), 3 * s.num_points, rank)
                .cast<float>();
  const std::vector<double> nodes = r.Numbers(g + "contact_nodes", {0}, &shape);
  const hsize_t J = positive(shape[0], "contact_nodes");
  s.contact_nodes.resize(J);
  WholeNumbers(r, nodes, g + "contact_nodes", &s.contact_nodes);
  const std::vector<double> mixing = r.Numbers(g + "mixing", {static_cast<hsize_t>(rank), J});
  s.mixing = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      mixing.data(), rank, static_cast<Eigen::Index>(J));
  const std::vector<double> lift = r.Numbers(g + "lift", {J});
  s.lift = Eigen::Map<const Eigen::VectorXd>(lift.data(), static_cast<Eigen::Index>(J));
  const std::vector<double> z = r.Numbers(g + "quadrature_z", {0}, &shape);
  const hsize_t Q = positive(shape[0], "quadrature_z");
  s.quadrature_z = Eigen::Map<const Eigen::VectorXd>(z.data(), static_cast<Eigen::Index>(Q));
  const std::vector<double> weight = r.Numbers(g + "quadrature_weight", {Q});
  s.quadrature_weight = Eigen::Map<const Eigen::VectorXd>(weight.data(), static_cast<Eigen::Index>(Q));
  const std::vector<double> contact = r.Numbers(g + "quadrature_contact", {Q, 6});
  Eigen::Matrix<std::int32_t, Eigen::Dynamic, 6, Eigen::RowMajor> c(static_cast<Eigen::Index>(Q), 6);
  Eigen::Map<Eigen::Matrix<std::int32_t, Eigen::Dynamic, 1>> flat(c.data(), c.size());
  WholeNumbers(r, contact, g + "quadrature_contact", &flat);
  s.quadrature_contact = c;
  const std::vector<double> N = r.Numbers(g + "quadrature_N", {Q, 6});
  s.quadrature_N = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor>>(
      N.data(), static_cast<Eigen::Index>(Q), 6);
  const std::vector<double> sv = r.Numbers(g + "singular_values", {0}, &shape);
  s.singular_values = Eigen::Map<const Eigen::VectorXd>(sv.data(), static_cast<Eigen::Index>(shape[0]));
  // The basis' own checks (indices, order, shapes), naming the file.
  try {
    BarResponseBasis check(s, source);
  } catch (const Error& e) {
    r.Bad(std::string("/") + g + ": " + e.what());
  }
  return b;
}

// The dataset of an open file, checked against the layout of the header.
FemDataset ReadOpenFemDataset(const Reader& r) {
  FemDataset d;
  const std::vector<double> position = r.Numbers("load_cases/position", {0});
  const hsize_t cases = position.size();
  if (cases == 0) r.Bad("/load_cases/position lists no load case");
  const std::vector<double> force = r.Numbers("load_cases/force_n", {cases});
  d.position = Eigen::Map<const Eigen::VectorXd>(position.data(), static_cast<Eigen::Index>(cases));
  d.force_n = Eigen::Map<const Eigen::VectorXd>(force.data(), static_cast<Eigen::Index>(cases));
  if ((d.position.array() < 0.0).any() || (d.position.array() > 1.0).any())
    r.Bad("/load_cases/position must be fractions of the sternal length (0 to 1)");

  std::vector<hsize_t> shape;
  const std::vector<double> faces = r.Numbers("topology/faces", {0, 3}, &shape);
  const hsize_t nf = shape[0];
  const std::vector<double> region = r.Numbers("topology/face_region", {nf});
  const std::vector<double> part = r.Numbers("topology/face_part", {nf});
  d.faces.resize(static_cast<Eigen::Index>(nf), 3);
  d.face_region.resize(static_cast<Eigen::Index>(nf));
  d.face_part.resize(static_cast<Eigen::Index>(nf));
  for (std::size_t f = 0; f < nf; ++f) {
    for (std::size_t c = 0; c < 3; ++c) {
      const double v = faces[3 * f + c];
      if (v != std::floor(v) || v < 0 || v > 2e9)
        r.Bad("/topology/faces holds " + std::to_string(v) + ", not a node index");
      d.faces(static_cast<Eigen::Index>(f), static_cast<Eigen::Index>(c)) = static_cast<std::int32_t>(v);
    }
    if (region[f] != 0 && region[f] != 1 && region[f] != 2)
      r.Bad("/topology/face_region holds a region other than 0, 1, 2");
    if (part[f] != std::floor(part[f]) || std::abs(part[f]) > 1e6)
      r.Bad("/topology/face_part holds a part that is not a rib number");
    d.face_region[static_cast<Eigen::Index>(f)] = static_cast<int>(region[f]);
    d.face_part[static_cast<Eigen::Index>(f)] = static_cast<int>(part[f]);
  }

  for (const std::string& id : r.Members("patients")) {
    FemDataset::Patient p;
    p.id = id;
    const std::string group = "patients/" + id + "/";
    const std::vector<double> nodes = r.Numbers(group + "nodes", {0, 3}, &shape);
    const hsize_t n = shape[0];
    if (!d.patients.empty() && static_cast<Eigen::Index>(n) != d.patients.front().nodes_mm.rows())
      r.Bad("/" + group + "nodes has " + std::to_string(n) + " nodes, the first patient " +
            std::to_string(d.patients.front().nodes_mm.rows()));
    if (nf > 0 && static_cast<Eigen::Index>(n) <= d.faces.maxCoeff())
      r.Bad("/topology/faces refers to node " + std::to_string(d.faces.maxCoeff()) + " of " +
            std::to_string(n) + " surface nodes");
    p.nodes_mm = Eigen::Map<const Points3>(nodes.data(), static_cast<Eigen::Index>(n), 3);
    const std::vector<double> u = r.Numbers(group + "displacements", {cases, n, 3});
    for (std::size_t k = 0; k < cases; ++k)
      p.displacements_mm.push_back(
          Eigen::Map<const Points3>(u.data() + k * n * 3, static_cast<Eigen::Index>(n), 3));
    const std::vector<double> lift = r.Numbers(group + "sternum_lift", {cases});
    p.sternum_lift_mm = Eigen::Map<const Eigen::VectorXd>(lift.data(), static_cast<Eigen::Index>(cases));
    if (r.Exists(group + "response_basis")) p.basis = ReadResponseBasis(r, group, r.name());
    d.patients.push_back(std::move(p));
  }
  return d;
}

}  // namespace

FemDataset ReadFemDataset(const std::filesystem::path& path) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) ThrowBadInput(path.string(), "no such file");
  const hid_t file = H5Fis_hdf5(path.c_str()) > 0 ? H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT) : -1;
  if (file < 0) ThrowBadInput(path.string(), "is not an HDF5 file");
  return ReadOpenFemDataset(Reader(file, path.string()));
}

StoredResponseBasis ReadStoredResponseBasis(const std::filesystem::path& path, const std::string& patient) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) ThrowBadInput(path.string(), "no such file");
  const hid_t file = H5Fis_hdf5(path.c_str()) > 0 ? H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT) : -1;
  if (file < 0) ThrowBadInput(path.string(), "is not an HDF5 file");
  const Reader r(file, path.string());
  if (patient.empty() || patient.find('/') != std::string::npos || !r.Exists("patients/" + patient))
    r.Bad("has no patient '" + patient + "' (under /patients)");
  if (!r.Exists("patients/" + patient + "/response_basis"))
    r.Bad("has no response basis for patient " + patient +
          " (write the dataset with `pectus surrogate build`)");
  return ReadResponseBasis(r, "patients/" + patient + "/", path.string());
}

namespace {

// The bytes of dataset `name` of an open file, as stored (its own type): to compare two files' headers.
std::vector<char> StoredBytes(const Reader& r, hid_t file, const std::string& name) {
  if (!r.Exists(name)) r.Bad("has no dataset /" + name);
  const hid_t set = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
  const hid_t type = set < 0 ? -1 : H5Dget_type(set), space = set < 0 ? -1 : H5Dget_space(set);
  std::vector<char> bytes;
  bool ok = set >= 0 && type >= 0 && space >= 0;
  if (ok) {
    bytes.resize(H5Tget_size(type) * static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
    ok = bytes.empty() || H5Dread(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, bytes.data()) >= 0;
  }
  if (space >= 0) H5Sclose(space);
  if (type >= 0) H5Tclose(type);
  if (set >= 0) H5Dclose(set);
  if (!ok) r.Bad("/" + name + " cannot be read");
  return bytes;
}

// Copies every attribute of `from` onto `to` (fixed-size types, as the writer makes them), in name order.
void CopyAttributes(hid_t from, hid_t to, const Reader& r, const std::filesystem::path& path) {
  struct Copy {
    hid_t to;
    bool ok = true;
  } copy{to};
  const auto one = [](hid_t object, const char* name, const H5A_info_t*, void* data) -> herr_t {
    auto* c = static_cast<Copy*>(data);
    const hid_t a = H5Aopen(object, name, H5P_DEFAULT);
    const hid_t type = a < 0 ? -1 : H5Aget_type(a), space = a < 0 ? -1 : H5Aget_space(a);
    if (type < 0 || space < 0 || H5Tis_variable_str(type) != 0) {
      c->ok = false;
    } else {
      std::vector<char> bytes(H5Tget_size(type) *
                              static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
      const hid_t b = H5Aread(a, type, bytes.data()) < 0
                          ? -1
                          : H5Acreate2(c->to, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
      c->ok = b >= 0 && H5Awrite(b, type, bytes.data()) >= 0;
      if (b >= 0) H5Aclose(b);
    }
    if (space >= 0) H5Sclose(space);
    if (type >= 0) H5Tclose(type);
    if (a >= 0) H5Aclose(a);
    return c->ok ? 0 : -1;
  };
  if (H5Aiterate2(from, H5_INDEX_NAME, H5_ITER_INC, nullptr, one, &copy) < 0 || !copy.ok)
    r.Bad("its attributes cannot be copied into " + path.string());
}

// Copies object `name` of `from` to `to_parent`/`to_name` as stored (chunks not decompressed).
void CopyObject(hid_t from, const std::string& name, hid_t to_parent, const std::string& to_name,
                const Reader& r, const std::filesystem::path& path) {
  if (H5Ocopy(from, name.c_str(), to_parent, to_name.c_str(), H5P_DEFAULT, H5P_DEFAULT) < 0)
    r.Bad("/" + name + " cannot be copied into " + path.string());
}

}  // namespace

FemDatasetAssembly AssembleFemDataset(const std::vector<std::filesystem::path>& parts,
                                      const std::filesystem::path& path) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  if (parts.empty()) ThrowUsage("FE dataset: no patient to assemble into " + path.string());
  std::vector<std::unique_ptr<Reader>> readers;
  std::vector<hid_t> files;
  FemDatasetAssembly assembly;
  std::vector<std::string>& ids = assembly.patients;
  for (const std::filesystem::path& part : parts) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(part, ec))
      ThrowBadInput(part.string(), "no such file (a dataset part)");
    const hid_t file = H5Fis_hdf5(part.c_str()) > 0 ? H5Fopen(part.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT) : -1;
    if (file < 0) ThrowBadInput(part.string(), "is not an HDF5 file");
    readers.push_back(std::make_unique<Reader>(file, part.string()));
    files.push_back(file);
    const Reader& r = *readers.back();
    const std::vector<std::string> members = r.Members("patients");
    if (members.size() != 1) r.Bad("holds " + std::to_string(members.size()) + " patients; a part holds one");
    if (std::find(ids.begin(), ids.end(), members[0]) != ids.end())
      r.Bad("holds patient " + members[0] + ", whom another part holds too");
    ids.push_back(members[0]);
    // Every part was made with the first's load cases and generic ribcage (the same options).
    if (readers.size() == 1) {
      assembly.load_cases = static_cast<std::int64_t>(r.Numbers("load_cases/position", {0}).size());
      std::vector<hsize_t> shape;
      r.Numbers("patients/" + members[0] + "/nodes", {0, 3}, &shape);
      assembly.surface_nodes = static_cast<std::int64_t>(shape[0]);
    } else {
      for (const char* shared : {"load_cases/position", "load_cases/force_n", "topology/faces"}) {
        if (StoredBytes(r, file, shared) != StoredBytes(*readers.front(), files.front(), shared))
          r.Bad(std::string("/") + shared + " differs from that of " + parts.front().string() +
                ": the parts were made with other options");
      }
    }
  }
  OutputTransaction output;
  const std::filesystem::path temp = output.Stage(path);
  {
    struct Closer {
      hid_t file = -1, patients = -1;
      ~Closer() {
        if (patients >= 0) H5Gclose(patients);
        if (file >= 0) H5Fclose(file);
      }
    } out;
    out.file = CreateReproducibleFile(temp, path);
    // The header (attributes, load cases, topology) from the first part, then each part's patient.
    CopyAttributes(files.front(), out.file, *readers.front(), path);
    CopyObject(files.front(), "load_cases", out.file, "load_cases", *readers.front(), path);
    CopyObject(files.front(), "topology", out.file, "topology", *readers.front(), path);
    out.patients = Group(out.file, "patients", path);
    for (std::size_t k = 0; k < parts.size(); ++k)
      CopyObject(files[k], "patients/" + ids[k], out.patients, ids[k], *readers[k], path);
  }
  readers.clear();
  output.CommitAll();
  return assembly;
}

FemDataset ParseFemDataset(std::string_view bytes, const std::string& name) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  // The core (memory) driver over a copy of the bytes, never written back: HDF5's file image.
  const hid_t access = H5Pcreate(H5P_FILE_ACCESS);
  hid_t file = -1;
  if (access >= 0 && !bytes.empty() && H5Pset_fapl_core(access, 1 << 16, /*backing_store=*/false) >= 0 &&
      H5Pset_file_image(access, const_cast<char*>(bytes.data()), bytes.size()) >= 0) {
    file = H5Fopen(name.c_str(), H5F_ACC_RDONLY, access);
  }
  if (access >= 0) H5Pclose(access);
  if (file < 0) ThrowBadInput(name, "is not an HDF5 file");
  return ReadOpenFemDataset(Reader(file, name));
}

}  // namespace pectus::planner
