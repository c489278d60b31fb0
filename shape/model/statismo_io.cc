#include "shape/model/statismo_io.h"

#include <hdf5.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include "shape/core/atomic_file.h"
#include "shape/core/error.h"
#include "shape/model/shape_grid.h"

namespace pectus {
namespace {

using RowMajorF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using RowMajorD = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using RowMajorI = Eigen::Matrix<std::int32_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// An HDF5 identifier closed on destruction.
class Id {
 public:
  Id(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Id() {
    if (id_ >= 0) close_(id_);
  }
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

// The largest dataset read, in numbers (2^31: beyond any shape model, and within Eigen's index).
constexpr hsize_t kMaxElements = hsize_t{1} << 31;

// Every HDF5 call of one file goes through this, so that a failure names the file and the object.
struct File {
  std::string name;  // for messages

  [[noreturn]] void Fail(const std::string& what) const { ThrowFailure("HDF5 could not " + what, name); }
  [[noreturn]] void Bad(const std::string& what) const { ThrowBadInput(name, what); }

  // Objects are made without modification times, so that one model is always written as the same bytes
  // (with SOURCE_DATE_EPOCH for the build times, Now()).
  hid_t Group(hid_t parent, const std::string& path) const {
    const Id properties(H5Pcreate(H5P_GROUP_CREATE), H5Pclose);
    H5Pset_obj_track_times(properties.get(), false);
    const hid_t g = H5Gcreate2(parent, path.c_str(), H5P_DEFAULT, properties.get(), H5P_DEFAULT);
    if (g < 0) Fail("create group " + path);
    return g;
  }
  void Array(hid_t loc, const std::string& path, hid_t type, const std::vector<hsize_t>& dims,
             const void* data) const {
    Id space(dims.empty() ? H5Screate(H5S_SCALAR)
                          : H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr),
             H5Sclose);
    const Id properties(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    H5Pset_obj_track_times(properties.get(), false);
    Id set(H5Dcreate2(loc, path.c_str(), type, space.get(), H5P_DEFAULT, properties.get(), H5P_DEFAULT),
           H5Dclose);
    if (!space.ok() || !set.ok() || H5Dwrite(set.get(), type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
      Fail("write " + path);
    }
  }
  void String(hid_t loc, const std::string& path, const std::string& text) const {
    Id type(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(type.get(), text.size() + 1);
    Array(loc, path, type.get(), {}, text.c_str());
  }
  void StringAttribute(hid_t loc, const std::string& attribute, const std::string& text) const {
    Id type(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(type.get(), text.size() + 1);
    Id space(H5Screate(H5S_SCALAR), H5Sclose);
    Id attr(H5Acreate2(loc, attribute.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
    if (!attr.ok() || H5Awrite(attr.get(), type.get(), text.c_str()) < 0)
      Fail("write attribute " + attribute);
  }

  bool Exists(hid_t loc, const std::string& path) const {
    std::size_t start = 0;
    while (true) {
      const std::size_t slash = path.find('/', start);
      const std::string prefix = path.substr(0, slash);
      if (H5Lexists(loc, prefix.c_str(), H5P_DEFAULT) <= 0) return false;
      if (slash == std::string::npos) return true;
      start = slash + 1;
    }
  }
  std::vector<hsize_t> Dims(hid_t set, const std::string& path) const {
    Id space(H5Dget_space(set), H5Sclose);
    const int rank = H5Sget_simple_extent_ndims(space.get());
    if (rank < 0) Bad("cannot read the shape of " + path);
    std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
    H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
    return dims;
  }
  // Reads a numeric dataset converted to `memory_type`; `dims` gets its shape.
  template <class T>
  std::vector<T> Read(hid_t loc, const std::string& path, hid_t memory_type,
                      std::vector<hsize_t>* dims) const {
    if (!Exists(loc, path)) Bad("has no dataset /" + path);
    Id set(H5Dopen2(loc, path.c_str(), H5P_DEFAULT), H5Dclose);
    if (!set.ok()) Bad("cannot open /" + path);
    *dims = Dims(set.get(), path);
    hsize_t count = 1;
    for (hsize_t d : *dims) {
      if (d > 0 && count > kMaxElements / d) Bad("/" + path + " is too large (over 2^31 numbers)");
      count *= d;
    }
    Id file_type(H5Dget_type(set.get()), H5Tclose);
    const H5T_class_t cls = H5Tget_class(file_type.get());
    if (cls != H5T_FLOAT && cls != H5T_INTEGER) Bad("/" + path + " is not numeric");
    // A dataset may declare a shape without storing it (HDF5 then reads its fill value): not a model.
    if (count > 0 && H5Dget_storage_size(set.get()) == 0) Bad("/" + path + " holds no data");
    std::vector<T> data(static_cast<std::size_t>(count));
    if (count > 0 && H5Dread(set.get(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()) < 0) {
      Bad("cannot read /" + path);
    }
    return data;
  }
  // Reads a numeric dataset that must hold exactly one number.
  double ReadScalar(hid_t loc, const std::string& path) const {
    std::vector<hsize_t> dims;
    const std::vector<double> value = Read<double>(loc, path, H5T_NATIVE_DOUBLE, &dims);
    if (value.size() != 1) Bad("/" + path + " must hold one number, not " + std::to_string(value.size()));
    return value[0];
  }
  std::string ReadString(hid_t loc, const std::string& path) const {
    if (!Exists(loc, path)) Bad("has no dataset /" + path);
    Id set(H5Dopen2(loc, path.c_str(), H5P_DEFAULT), H5Dclose);
    Id type(H5Dget_type(set.get()), H5Tclose);
    if (!set.ok() || H5Tget_class(type.get()) != H5T_STRING) Bad("/" + path + " is not a string");
    return ReadText(
        type.get(),
        [&](hid_t mem, void* buf) { return H5Dread(set.get(), mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf); },
        path);
  }
  std::string ReadStringAttribute(hid_t loc, const std::string& attribute, const std::string& where) const {
    if (H5Aexists(loc, attribute.c_str()) <= 0) Bad(where + " has no attribute '" + attribute + "'");
    Id attr(H5Aopen(loc, attribute.c_str(), H5P_DEFAULT), H5Aclose);
    Id type(H5Aget_type(attr.get()), H5Tclose);
    if (!attr.ok() || H5Tget_class(type.get()) != H5T_STRING)
      Bad(where + " attribute '" + attribute + "' is not a string");
    return ReadText(
        type.get(), [&](hid_t mem, void* buf) { return H5Aread(attr.get(), mem, buf); },
        where + "@" + attribute);
  }
  template <class ReadFn>
  std::string ReadText(hid_t file_type, ReadFn read, const std::string& what) const {
    if (H5Tis_variable_str(file_type) > 0) {
      Id mem(H5Tcopy(H5T_C_S1), H5Tclose);
      H5Tset_size(mem.get(), H5T_VARIABLE);
      char* text = nullptr;
      if (read(mem.get(), &text) < 0 || text == nullptr) Bad("cannot read " + what);
      std::string s(text);
      H5free_memory(text);
      return s;
    }
    const std::size_t size = H5Tget_size(file_type);
    Id mem(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(mem.get(), size + 1);
    std::vector<char> buffer(size + 1, '\0');
    if (read(mem.get(), buffer.data()) < 0) Bad("cannot read " + what);
    return std::string(buffer.data());
  }
};

// The build time statismo records: now, local time; or, when the environment sets SOURCE_DATE_EPOCH (the
// reproducible-builds convention: seconds since 1970), that time in UTC, so that a rerun gives the same
// bytes.
std::string Now() {
  std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm when{};
  const char* epoch = std::getenv("SOURCE_DATE_EPOCH");
  if (epoch != nullptr && *epoch != '\0') {
    t = static_cast<std::time_t>(std::strtoll(epoch, nullptr, 10));
    gmtime_r(&t, &when);
  } else {
    localtime_r(&t, &when);
  }
  char text[64];
  std::strftime(text, sizeof(text), "%a %b %d %H:%M:%S %Y", &when);
  return text;
}

}  // namespace

void WriteStatismoModel(const std::filesystem::path& path, const ShapeModel& model,
                        const nlohmann::json& info) {
  model.Validate(path.string());
  if (model.num_modes() == 0)
    ThrowUsage("a model without modes cannot be written as a statismo file: " + path.string());
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors become pectus::Error, not prints
  const File f{path.string()};
  OutputTransaction output;  // HDF5 writes to a file name: a staged file, renamed into place at the end
  const std::filesystem::path temp = output.Stage(path);
  {
    Id file(H5Fcreate(temp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
    if (!file.ok()) f.Fail("create the file");
    const hid_t root = file.get();
    const auto m = static_cast<hsize_t>(model.num_points());
    const auto k = static_cast<hsize_t>(model.num_modes());

    {  // Format version.
      Id g(f.Group(root, "version"), H5Gclose);
      const std::int32_t major = 0, minor = 9;
      f.Array(g.get(), "majorVersion", H5T_NATIVE_INT32, {}, &major);
      f.Array(g.get(), "minorVersion", H5T_NATIVE_INT32, {}, &minor);
    }
    {  // The representer: the reference mesh (the mean shape) as points [3, m] and cells [3, #faces].
      Id g(f.Group(root, "representer"), H5Gclose);
      f.StringAttribute(g.get(), "name", "itkStandardMeshRepresenter");
      f.StringAttribute(g.get(), "version", "1.0");
      f.StringAttribute(g.get(), "datasetType", model.faces.rows() > 0 ? "POLYGON_MESH" : "POINT_SET");
      const RowMajorF points = FromShapeVector(model.mean).transpose().cast<float>();
      f.Array(g.get(), "points", H5T_NATIVE_FLOAT, {3, m}, points.data());
      if (model.faces.rows() > 0) {
        const RowMajorI cells = model.faces.transpose();
        f.Array(g.get(), "cells", H5T_NATIVE_INT32, {3, static_cast<hsize_t>(model.faces.rows())},
                cells.data());
      }
      Id data(f.Group(g.get(), "pointData"), H5Gclose);
    }
    {  // The model: mean, orthonormal basis, variances, noise.
      Id g(f.Group(root, "model"), H5Gclose);
      const Eigen::VectorXf mean = model.mean.cast<float>();
      const RowMajorF basis = model.basis.cast<float>();
      const Eigen::VectorXf variances = model.variances.cast<float>();
      const auto noise = static_cast<float>(model.noise_variance);
      f.Array(g.get(), "mean", H5T_NATIVE_FLOAT, {3 * m}, mean.data());
      f.Array(g.get(), "pcaBasis", H5T_NATIVE_FLOAT, {3 * m, k}, basis.data());
      f.Array(g.get(), "pcaVariance", H5T_NATIVE_FLOAT, {k}, variances.data());
      f.Array(g.get(), "noiseVariance", H5T_NATIVE_FLOAT, {}, &noise);
    }
    {  // Model information as statismo's ModelInfo writes it; scores are k x N (a column per subject).
      Id g(f.Group(root, "modelinfo"), H5Gclose);
      f.String(g.get(), "build-time", Now());
      if (model.scores.size() > 0) {
        const RowMajorF scores = model.scores.transpose().cast<float>();
        f.Array(g.get(), "scores", H5T_NATIVE_FLOAT, {k, static_cast<hsize_t>(model.scores.rows())},
                scores.data());
      } else {
        const float zero = 0.0f;
        f.Array(g.get(), "scores", H5T_NATIVE_FLOAT, {1, 1}, &zero);
      }
      Id b(f.Group(g.get(), "modelBuilder-0"), H5Gclose);
      f.String(b.get(), "builderName", "pectus PCA (Gram matrix)");
      f.String(b.get(), "buildTime", Now());
      Id data(f.Group(b.get(), "dataInfo"), H5Gclose);
      for (std::size_t n = 0; n < model.names.size(); ++n)
        f.String(data.get(), "URI_" + std::to_string(n), model.names[n]);
      Id parameters(f.Group(b.get(), "parameters"), H5Gclose);
      f.String(parameters.get(), "NoiseVariance", std::to_string(model.noise_variance));
    }
    {  // pectus's own: the total variance (for exact explained fractions) and free-form information.
      Id g(f.Group(root, "pectus"), H5Gclose);
      f.Array(g.get(), "totalVariance", H5T_NATIVE_DOUBLE, {}, &model.total_variance);
      f.String(g.get(), "info", info.dump());
    }
    if (H5Fflush(root, H5F_SCOPE_GLOBAL) < 0) f.Fail("flush the file");
  }
  output.CommitAll();
}

namespace {

// Reads the model of an open statismo file (from a path or from memory); `f` names it in errors.
ShapeModel ReadOpenStatismoFile(const File& f, hid_t root, nlohmann::json* info) {
  double major = 0, minor = 8;  // statismo: a file without a version is 0.8
  std::vector<hsize_t> dims;
  if (f.Exists(root, "version/majorVersion")) {
    major = f.ReadScalar(root, "version/majorVersion");
    minor = f.ReadScalar(root, "version/minorVersion");
  }
  if (!(major == 0 && (minor == 8 || minor == 9)) && major != 1) {
    const auto number = [](double v) {
      return v == std::floor(v) && std::abs(v) < 1e9 ? std::to_string(static_cast<std::int64_t>(v))
                                                     : std::to_string(v);
    };
    f.Bad("statismo version " + number(major) + "." + number(minor) + " is not supported (0.8, 0.9, 1.x)");
  }

  ShapeModel model;
  const std::vector<double> mean = f.Read<double>(root, "model/mean", H5T_NATIVE_DOUBLE, &dims);
  if (dims.size() != 1 || mean.empty() || mean.size() % 3 != 0)
    f.Bad("/model/mean must be a vector of 3m numbers");
  const auto d = static_cast<Eigen::Index>(mean.size());
  model.mean = Eigen::Map<const Eigen::VectorXd>(mean.data(), d);
  const std::vector<double> variances = f.Read<double>(root, "model/pcaVariance", H5T_NATIVE_DOUBLE, &dims);
  if (dims.size() != 1) f.Bad("/model/pcaVariance must be a vector");
  const auto k = static_cast<Eigen::Index>(variances.size());
  model.variances = Eigen::Map<const Eigen::VectorXd>(variances.data(), k);
  const std::vector<double> basis = f.Read<double>(root, "model/pcaBasis", H5T_NATIVE_DOUBLE, &dims);
  if (dims.size() != 2 || static_cast<Eigen::Index>(dims[0]) != d ||
      static_cast<Eigen::Index>(dims[1]) != k) {
    f.Bad("/model/pcaBasis must be " + std::to_string(d) + " x " + std::to_string(k) + " (3m x modes)");
  }
  model.basis = Eigen::Map<const RowMajorD>(basis.data(), d, k);
  if (major == 0 && minor == 8) {  // 0.8 stored U D; divide the standard deviations out
    for (Eigen::Index c = 0; c < k; ++c) {
      if (model.variances[c] > 0.0) model.basis.col(c) /= std::sqrt(model.variances[c]);
    }
  }
  model.noise_variance = f.ReadScalar(root, "model/noiseVariance");

  // Topology from the representer (the points themselves are the reference, not needed here).
  if (!f.Exists(root, "representer")) f.Bad("has no /representer group");
  if (f.Exists(root, "representer/cells")) {
    const std::vector<std::int32_t> cells =
        f.Read<std::int32_t>(root, "representer/cells", H5T_NATIVE_INT32, &dims);
    if (dims.size() != 2 || dims[0] != 3) f.Bad("/representer/cells must be 3 x #triangles");
    model.faces =
        Eigen::Map<const RowMajorI>(cells.data(), 3, static_cast<Eigen::Index>(dims[1])).transpose();
  }

  // Scores (k x N) and names.
  if (f.Exists(root, "modelinfo/scores")) {
    const std::vector<double> scores = f.Read<double>(root, "modelinfo/scores", H5T_NATIVE_DOUBLE, &dims);
    if (dims.size() == 2 && static_cast<Eigen::Index>(dims[0]) == k && k > 0) {
      model.scores =
          Eigen::Map<const RowMajorD>(scores.data(), k, static_cast<Eigen::Index>(dims[1])).transpose();
    }
  }
  for (std::size_t n = 0; n < static_cast<std::size_t>(model.scores.rows()); ++n) {
    const std::string key = "modelinfo/modelBuilder-0/dataInfo/URI_" + std::to_string(n);
    if (!f.Exists(root, key)) {
      model.names.clear();
      break;
    }
    model.names.push_back(f.ReadString(root, key));
  }
  model.total_variance = model.variances.sum();
  if (f.Exists(root, "pectus/totalVariance")) {
    model.total_variance = f.ReadScalar(root, "pectus/totalVariance");
  }
  if (info != nullptr) {
    *info = nlohmann::json::object();
    if (f.Exists(root, "pectus/info")) {
      *info = nlohmann::json::parse(f.ReadString(root, "pectus/info"), nullptr, false);
      if (info->is_discarded()) f.Bad("/pectus/info is not JSON");
    }
  }
  model.Validate(f.name);
  return model;
}

}  // namespace

ShapeModel ReadStatismoModel(const std::filesystem::path& path, nlohmann::json* info) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const File f{path.string()};
  if (!std::filesystem::exists(path)) ThrowBadInput(path.string(), "no such file");
  if (H5Fis_hdf5(path.c_str()) <= 0) f.Bad("is not an HDF5 file");
  Id file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!file.ok()) f.Bad("cannot be opened as HDF5");
  return ReadOpenStatismoFile(f, file.get(), info);
}

ShapeModel ParseStatismoModel(std::string_view bytes, const std::string& name, nlohmann::json* info) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const File f{name};
  if (bytes.empty()) f.Bad("is empty, not an HDF5 file");
  // The core (memory) driver over a copy of the bytes, never written back: HDF5's file image.
  Id access(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  if (!access.ok() || H5Pset_fapl_core(access.get(), 1 << 16, /*backing_store=*/false) < 0 ||
      H5Pset_file_image(access.get(), const_cast<char*>(bytes.data()), bytes.size()) < 0) {
    f.Fail("hold the file in memory");
  }
  Id file(H5Fopen(name.c_str(), H5F_ACC_RDONLY, access.get()), H5Fclose);
  if (!file.ok()) f.Bad("is not an HDF5 file");
  return ReadOpenStatismoFile(f, file.get(), info);
}

}  // namespace pectus
