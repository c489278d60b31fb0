// The statismo HDF5 file: structure (groups, datasets, shapes, types, attributes) as statismo 0.9 and
// Scalismo read it, checked with the HDF5 C API directly; round trip through pectus.
#include "shape/model/statismo_io.h"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <vector>

#include "shape/core/error.h"
#include "shape/model/shape_grid.h"
#include "tests/support/bad_input.h"

namespace pectus {
namespace {
namespace fs = std::filesystem;
using testing_support::BadInputMessage;

// A model over a 4 x 3 grid mesh (12 vertices, 12 triangles) from 5 random shapes.
ShapeModel SmallModel() {
  const GridSize g{4, 3};
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 2.0);
  Eigen::MatrixXd shapes(5, 3 * g.num_vertices());
  for (Eigen::Index r = 0; r < shapes.rows(); ++r) {
    for (Eigen::Index c = 0; c < shapes.cols(); ++c)
      shapes(r, c) = 10.0 * static_cast<double>(c % 5) + n(rng);
  }
  ShapeModelOptions o;
  o.noise_variance = 0.25;
  ShapeModel m = BuildShapeModel(shapes, o);
  m.faces = GridFaces(g);
  m.names = {"s0", "s1", "s2", "s3", "s4"};
  return m;
}

class StatismoIo : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("pectus_statismo_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

std::vector<hsize_t> Dims(hid_t file, const char* path, H5T_class_t* cls, std::size_t* size) {
  const hid_t set = H5Dopen2(file, path, H5P_DEFAULT);
  EXPECT_GE(set, 0) << path;
  if (set < 0) return {};
  const hid_t space = H5Dget_space(set), type = H5Dget_type(set);
  std::vector<hsize_t> dims(static_cast<std::size_t>(H5Sget_simple_extent_ndims(space)));
  H5Sget_simple_extent_dims(space, dims.data(), nullptr);
  *cls = H5Tget_class(type);
  *size = H5Tget_size(type);
  H5Tclose(type);
  H5Sclose(space);
  H5Dclose(set);
  return dims;
}

std::string StringAttribute(hid_t file, const char* object, const char* name) {
  const hid_t attr = H5Aopen_by_name(file, object, name, H5P_DEFAULT, H5P_DEFAULT);
  EXPECT_GE(attr, 0) << object << "@" << name;
  if (attr < 0) return {};
  const hid_t type = H5Aget_type(attr);
  std::string text(H5Tget_size(type), '\0');
  H5Aread(attr, type, text.data());
  H5Tclose(type);
  H5Aclose(attr);
  return text.c_str();
}

TEST_F(StatismoIo, FileHasTheStatismo09Structure) {
  const ShapeModel m = SmallModel();
  const fs::path path = dir_ / "model.h5";
  WriteStatismoModel(path, m, {{"grid", {4, 3}}});
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  const hsize_t n3 = 36, k = static_cast<hsize_t>(m.num_modes());
  H5T_class_t cls;
  std::size_t size;
  // Version: scalar int32 datasets 0 and 9.
  for (const char* p : {"/version/majorVersion", "/version/minorVersion"}) {
    EXPECT_TRUE(Dims(f, p, &cls, &size).empty()) << p;
    EXPECT_EQ(cls, H5T_INTEGER);
    EXPECT_EQ(size, 4u);
  }
  std::int32_t major = -1, minor = -1;
  hid_t set = H5Dopen2(f, "/version/majorVersion", H5P_DEFAULT);
  H5Dread(set, H5T_NATIVE_INT32, H5S_ALL, H5S_ALL, H5P_DEFAULT, &major);
  H5Dclose(set);
  set = H5Dopen2(f, "/version/minorVersion", H5P_DEFAULT);
  H5Dread(set, H5T_NATIVE_INT32, H5S_ALL, H5S_ALL, H5P_DEFAULT, &minor);
  H5Dclose(set);
  EXPECT_EQ(major, 0);
  EXPECT_EQ(minor, 9);
  // Model: float32 mean [3m], basis [3m, k], variance [k], scalar noise.
  EXPECT_EQ(Dims(f, "/model/mean", &cls, &size), std::vector<hsize_t>({n3}));
  EXPECT_EQ(cls, H5T_FLOAT);
  EXPECT_EQ(size, 4u);
  EXPECT_EQ(Dims(f, "/model/pcaBasis", &cls, &size), std::vector<hsize_t>({n3, k}));
  EXPECT_EQ(size, 4u);
  EXPECT_EQ(Dims(f, "/model/pcaVariance", &cls, &size), std::vector<hsize_t>({k}));
  EXPECT_TRUE(Dims(f, "/model/noiseVariance", &cls, &size).empty());
  EXPECT_EQ(cls, H5T_FLOAT);
  // The basis in the file is orthonormal (row-major 3m x k).
  Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> basis(n3, k);
  set = H5Dopen2(f, "/model/pcaBasis", H5P_DEFAULT);
  H5Dread(set, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, basis.data());
  H5Dclose(set);
  EXPECT_TRUE((basis.transpose() * basis).isIdentity(1e-5f));
  EXPECT_TRUE(basis.cast<double>().isApprox(m.basis, 1e-5));
  // Representer: attributes, points [3, m] float32, cells [3, #faces] int32.
  EXPECT_EQ(StringAttribute(f, "/representer", "name"), "itkStandardMeshRepresenter");
  EXPECT_EQ(StringAttribute(f, "/representer", "datasetType"), "POLYGON_MESH");
  EXPECT_EQ(Dims(f, "/representer/points", &cls, &size), std::vector<hsize_t>({3, 12}));
  EXPECT_EQ(cls, H5T_FLOAT);
  EXPECT_EQ(Dims(f, "/representer/cells", &cls, &size), std::vector<hsize_t>({3, 12}));
  EXPECT_EQ(cls, H5T_INTEGER);
  // points row d, column i is coordinate d of vertex i of the mean.
  Eigen::Matrix<float, 3, 12, Eigen::RowMajor> points;
  set = H5Dopen2(f, "/representer/points", H5P_DEFAULT);
  H5Dread(set, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, points.data());
  H5Dclose(set);
  EXPECT_NEAR(points(1, 5), m.mean[3 * 5 + 1], 1e-4);
  // Model info: scores [k, N], build time, builder, data URIs.
  EXPECT_EQ(Dims(f, "/modelinfo/scores", &cls, &size), std::vector<hsize_t>({k, 5}));
  EXPECT_TRUE(Dims(f, "/modelinfo/build-time", &cls, &size).empty());
  EXPECT_EQ(cls, H5T_STRING);
  EXPECT_TRUE(Dims(f, "/modelinfo/modelBuilder-0/builderName", &cls, &size).empty());
  EXPECT_TRUE(Dims(f, "/modelinfo/modelBuilder-0/dataInfo/URI_4", &cls, &size).empty());
  EXPECT_GT(H5Lexists(f, "/modelinfo/modelBuilder-0/parameters", H5P_DEFAULT), 0);
  H5Fclose(f);
}

TEST_F(StatismoIo, RoundTripKeepsTheModel) {
  const ShapeModel m = SmallModel();
  const fs::path path = dir_ / "model.h5";
  WriteStatismoModel(path, m, {{"grid", {4, 3}}});
  nlohmann::json info;
  const ShapeModel r = ReadStatismoModel(path, &info);
  EXPECT_TRUE(r.mean.isApprox(m.mean, 1e-6));
  EXPECT_TRUE(r.basis.isApprox(m.basis, 1e-5));
  EXPECT_TRUE(r.variances.isApprox(m.variances, 1e-6));
  EXPECT_TRUE(r.scores.isApprox(m.scores, 1e-5));
  EXPECT_EQ(r.faces, m.faces);
  EXPECT_EQ(r.names, m.names);
  EXPECT_NEAR(r.noise_variance, 0.25, 1e-7);
  EXPECT_DOUBLE_EQ(r.total_variance, m.total_variance);
  EXPECT_EQ(info["grid"], nlohmann::json({4, 3}));
  // No temporary file is left beside it.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

// Replaces dataset `path` of the file by an empty vector or a declared but never written one.
void ReplaceDataset(const fs::path& file, const char* path, hsize_t size, bool write) {
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  ASSERT_GE(H5Ldelete(f, path, H5P_DEFAULT), 0);
  const hid_t space = H5Screate_simple(1, &size, nullptr);
  const hid_t set = H5Dcreate2(f, path, H5T_NATIVE_FLOAT, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  ASSERT_GE(set, 0);
  const std::vector<float> zeros(size, 0.0f);
  if (write) H5Dwrite(set, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, zeros.data());
  H5Dclose(set);
  H5Sclose(space);
  H5Fclose(f);
}

TEST_F(StatismoIo, EmptyScalarsAndUnstoredDatasetsAreBadInput) {
  // Found by fuzzing: an empty /model/noiseVariance reached .at(0) and threw std::out_of_range.
  for (const char* path : {"/model/noiseVariance", "/version/majorVersion", "/pectus/totalVariance"}) {
    const fs::path file = dir_ / "empty_scalar.h5";
    WriteStatismoModel(file, SmallModel());
    ReplaceDataset(file, path, 0, false);
    const std::string what = BadInputMessage([&] { ReadStatismoModel(file); }, file.string());
    EXPECT_NE(what.find(std::string(path) + " must hold one number, not 0"), std::string::npos) << what;
  }
  // A mean that declares 36 numbers but stores none (HDF5 would read its fill value).
  const fs::path file = dir_ / "unstored.h5";
  WriteStatismoModel(file, SmallModel());
  ReplaceDataset(file, "/model/mean", 36, false);
  const std::string what = BadInputMessage([&] { ReadStatismoModel(file); }, file.string());
  EXPECT_NE(what.find("/model/mean holds no data"), std::string::npos) << what;
}

TEST_F(StatismoIo, ParseReadsTheSameModelFromMemory) {
  const ShapeModel m = SmallModel();
  const fs::path path = dir_ / "model.h5";
  WriteStatismoModel(path, m, {{"grid", {4, 3}}});
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  nlohmann::json info;
  const ShapeModel r = ParseStatismoModel(bytes, "memory.h5", &info);
  const ShapeModel f = ReadStatismoModel(path);
  // The same bytes through the same reader: identical numbers.
  EXPECT_EQ(r.mean, f.mean);
  EXPECT_EQ(r.basis, f.basis);
  EXPECT_EQ(r.variances, f.variances);
  EXPECT_EQ(r.scores, f.scores);
  EXPECT_EQ(r.faces, m.faces);
  EXPECT_EQ(r.names, m.names);
  EXPECT_EQ(info["grid"], nlohmann::json({4, 3}));
  for (const std::string& bad : {std::string(), std::string("hello"), bytes.substr(0, bytes.size() / 2)}) {
    BadInputMessage([&] { ParseStatismoModel(bad, "memory.h5"); }, "memory.h5");
  }
}

TEST_F(StatismoIo, BadFilesNameTheFileAndTheDataset) {
  const fs::path text = dir_ / "not.h5";
  std::ofstream(text) << "hello";
  try {
    ReadStatismoModel(text);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
    EXPECT_EQ(e.file(), text.string());
  }
  // An HDF5 file without /model.
  const fs::path empty = dir_ / "empty.h5";
  H5Fclose(H5Fcreate(empty.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
  try {
    ReadStatismoModel(empty);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/model/mean"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ReadStatismoModel(dir_ / "missing.h5"), Error);
}

}  // namespace
}  // namespace pectus
