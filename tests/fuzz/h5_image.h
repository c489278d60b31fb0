// Structure-aware HDF5 inputs for the fuzz targets of the .h5 readers: the fuzzer's bytes decide, for
// each object of a file layout, whether it is there as the layout says (with values perturbed by the
// bytes), missing, a group, a string, or a numeric dataset of another type and shape (empty, huge but
// unstored, ...). The file is built with HDF5's core driver and handed to the reader as a file image, so
// nothing touches the disk. An input of no bytes is the valid layout itself.
//
// Why not mutate the bytes of a file: libhdf5 itself is not hardened against corrupt files (its own
// parser is out of this project's reach), and byte mutations almost never get past its superblock checks
// to the readers' validation, which is what these targets test.
#pragma once

#include <hdf5.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace pectus::fuzz {

/// The fuzzer's bytes read from the front; zeros once they run out.
class Bytes {
 public:
  Bytes(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  std::uint8_t Next() {
    if (size_ == 0) return 0;
    --size_;
    return *data_++;
  }
  /// `base` for a 0 byte; NaN, +-Inf, a huge or a negative number for the top bytes; else a perturbation.
  double Value(double base) {
    const std::uint8_t b = Next();
    switch (b) {
      case 0: return base;
      case 255: return std::numeric_limits<double>::quiet_NaN();
      case 254: return std::numeric_limits<double>::infinity();
      case 253: return -std::numeric_limits<double>::infinity();
      case 252: return 1e300;
      case 251: return -base - 1.0;
      default: return base + (b - 128) / 8.0;
    }
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
};

/// One dataset of a layout: its path, its shape and values when valid, or its text for a string.
struct Slot {
  std::string path;
  std::vector<hsize_t> dims;       ///< shape of the valid dataset (empty: a scalar)
  std::vector<double> values;      ///< the valid values, row-major (ignored for a string)
  hid_t type = H5T_NATIVE_DOUBLE;  ///< the valid file type
  bool is_string = false;          ///< a string dataset holding `text`
  std::string text;
};

/// A numeric dataset of the layout.
inline Slot Numbers(std::string path, std::vector<hsize_t> dims, std::vector<double> values,
                    hid_t type = H5T_NATIVE_DOUBLE) {
  Slot slot;
  slot.path = std::move(path);
  slot.dims = std::move(dims);
  slot.values = std::move(values);
  slot.type = type;
  return slot;
}

/// A string dataset of the layout.
inline Slot Text(std::string path, std::string text) {
  Slot slot;
  slot.path = std::move(path);
  slot.is_string = true;
  slot.text = std::move(text);
  return slot;
}

/// Once per process: HDF5's errors off, and its free lists unbounded. Every file HDF5 creates or opens
/// allocates a metadata cache of several hundred KB; with the default limits the free lists hand it back to
/// malloc at close, so each run of a target maps and faults in fresh pages (half the run time went to the
/// kernel, at ~450 runs/s). Kept on HDF5's own lists, the blocks are reused.
inline void SetUpHdf5() {
  static const bool done = [] {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    H5set_free_list_limits(-1, -1, -1, -1, -1, -1);
    return true;
  }();
  (void)done;
}

/// Builds an HDF5 file in memory, slot by slot as the bytes decide; Image() returns its bytes.
class ImageBuilder {
 public:
  ImageBuilder() {
    SetUpHdf5();
    access_ = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_fapl_core(access_, 4096, /*backing_store=*/false);  // the images are a few KB
    file_ = H5Fcreate("pectus-fuzz-image.h5", H5F_ACC_TRUNC, H5P_DEFAULT, access_);
    links_ = H5Pcreate(H5P_LINK_CREATE);
    H5Pset_create_intermediate_group(links_, 1);
    // HDF5 allocates (and zeroes) its type-conversion buffer at every write: 1 MB by default, a third of
    // a run's time; 16 KB holds every dataset of these layouts a few times over.
    transfer_ = H5Pcreate(H5P_DATASET_XFER);
    H5Pset_buffer(transfer_, 16 * 1024, nullptr, nullptr);
    if (access_ < 0 || file_ < 0 || links_ < 0 || transfer_ < 0) std::abort();
  }
  ~ImageBuilder() {
    H5Pclose(transfer_);
    H5Pclose(links_);
    if (file_ >= 0) H5Fclose(file_);
    H5Pclose(access_);
  }
  ImageBuilder(const ImageBuilder&) = delete;
  ImageBuilder& operator=(const ImageBuilder&) = delete;

  /// Adds `slot` as the next byte decides: 0-3 valid, 4 missing, 5 a group, 6 a string, 7 another shape.
  void Add(const Slot& slot, Bytes* in) {
    const int mode = in->Next() % 8;
    if (mode == 4) return;
    if (mode == 5) {
      const hid_t g = H5Gcreate2(file_, slot.path.c_str(), links_, H5P_DEFAULT, H5P_DEFAULT);
      if (g >= 0) H5Gclose(g);
      return;
    }
    if (slot.is_string || mode == 6) {
      std::string text = slot.is_string ? slot.text : "";
      for (int n = in->Next() % 8; n > 0; --n) text += static_cast<char>(in->Next());
      WriteString(slot.path, text, in->Next() % 2 == 1);
      return;
    }
    if (mode < 4) {
      std::vector<double> values(slot.values.size());
      for (std::size_t i = 0; i < values.size(); ++i) values[i] = in->Value(slot.values[i]);
      WriteNumbers(slot.path, slot.type, slot.dims, values, /*store=*/true);
      return;
    }
    static const hid_t kTypes[] = {H5T_NATIVE_DOUBLE, H5T_NATIVE_FLOAT, H5T_NATIVE_INT32, H5T_NATIVE_UINT8,
                                   H5T_NATIVE_INT64};
    const hid_t type = kTypes[in->Next() % 5];
    std::vector<hsize_t> dims(in->Next() % 4);
    hsize_t count = 1;
    for (hsize_t& d : dims) {
      const std::uint8_t b = in->Next();
      d = b == 255 ? (hsize_t{1} << 33) : b % 7;  // 2^33: declared, never stored
      count *= d;
    }
    const bool store = count <= 4096;
    std::vector<double> values(store ? count : 0);
    for (double& v : values) v = in->Value(1.0);
    WriteNumbers(slot.path, type, dims, values, store);
  }

  /// The file's bytes (the builder is finished).
  std::vector<char> Image() {
    H5Fflush(file_, H5F_SCOPE_GLOBAL);
    const ssize_t size = H5Fget_file_image(file_, nullptr, 0);
    std::vector<char> image(size > 0 ? static_cast<std::size_t>(size) : 0);
    if (size > 0 && H5Fget_file_image(file_, image.data(), image.size()) < 0) std::abort();
    return image;
  }

 private:
  void WriteNumbers(const std::string& path, hid_t type, const std::vector<hsize_t>& dims,
                    const std::vector<double>& values, bool store) {
    const hid_t space = dims.empty() ? H5Screate(H5S_SCALAR)
                                     : H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr);
    const hid_t set = H5Dcreate2(file_, path.c_str(), type, space, links_, H5P_DEFAULT, H5P_DEFAULT);
    // Conversion of NaN or out-of-range values to an integer type is HDF5's business (it clips).
    if (set >= 0 && store && !values.empty()) {
      H5Dwrite(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, transfer_, values.data());
    }
    if (set >= 0) H5Dclose(set);
    H5Sclose(space);
  }
  void WriteString(const std::string& path, const std::string& text, bool variable) {
    const hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, variable ? H5T_VARIABLE : text.size() + 1);
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t set = H5Dcreate2(file_, path.c_str(), type, space, links_, H5P_DEFAULT, H5P_DEFAULT);
    const char* c = text.c_str();
    if (set >= 0)
      H5Dwrite(set, type, H5S_ALL, H5S_ALL, transfer_, variable ? static_cast<const void*>(&c) : c);
    if (set >= 0) H5Dclose(set);
    H5Sclose(space);
    H5Tclose(type);
  }

  hid_t access_ = -1, file_ = -1, links_ = -1, transfer_ = -1;
};

/// The file image of `layout` as the fuzzer's bytes decide (see ImageBuilder::Add).
inline std::vector<char> BuildImage(const std::vector<Slot>& layout, const std::uint8_t* data,
                                    std::size_t size) {
  Bytes in(data, size);
  ImageBuilder builder;
  for (const Slot& slot : layout) builder.Add(slot, &in);
  return builder.Image();
}

}  // namespace pectus::fuzz
