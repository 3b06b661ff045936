// HDF5 reading/writing with our own float16 conversion, silent HDF5 error stacks and a global lock
// (Debian's libhdf5 is not built thread-safe).
#include "io/hdf5_io.h"

#include <Imath/half.h>
#include <hdf5.h>

#include <cstring>
#include <filesystem>
#include <mutex>
#include <numeric>

#include "core/error.h"
#include "io/atomic_file.h"

namespace isplat {
namespace {

std::mutex& hdf5_mutex() {
  static std::mutex m;
  return m;
}

void silence_hdf5() {
  static std::once_flag once;
  std::call_once(once, [] {
    H5open();
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  });
}

// RAII for HDF5 ids.
struct H5Id {
  hid_t id = -1;
  herr_t (*close)(hid_t) = nullptr;
  H5Id(hid_t i, herr_t (*c)(hid_t)) : id(i), close(c) {}
  ~H5Id() {
    if (id >= 0 && close) close(id);
  }
  H5Id(const H5Id&) = delete;
  H5Id& operator=(const H5Id&) = delete;
  operator hid_t() const { return id; }
};

hid_t make_half_type() {
  hid_t t = H5Tcopy(H5T_IEEE_F32LE);
  H5Tset_fields(t, 15, 10, 5, 0, 10);
  H5Tset_size(t, 2);
  H5Tset_ebias(t, 15);
  return t;
}

// 2^28 elements: 1 GiB as float32, 100x a Hypersim frame.
constexpr uint64_t kMaxHdf5Elements = uint64_t{1} << 28;

struct Opened {
  std::vector<int64_t> shape;
  H5Type type;
  bool little_endian;
};

H5Type classify(const std::string& path, const std::string& dataset, hid_t dtype) {
  const H5T_class_t cls = H5Tget_class(dtype);
  const size_t size = H5Tget_size(dtype);
  if (cls == H5T_FLOAT) {
    if (size == 2) return H5Type::Float16;
    if (size == 4) return H5Type::Float32;
    if (size == 8) return H5Type::Float64;
  } else if (cls == H5T_INTEGER) {
    const bool is_signed = H5Tget_sign(dtype) == H5T_SGN_2;
    if (is_signed && size == 2) return H5Type::Int16;
    if (is_signed && size == 4) return H5Type::Int32;
    if (is_signed && size == 8) return H5Type::Int64;
    if (!is_signed && size == 1) return H5Type::UInt8;
  }
  static const char* class_names[] = {"integer",  "float",     "time", "string", "bitfield", "opaque",
                                      "compound", "reference", "enum", "vlen",   "array"};
  const std::string cname = cls >= 0 && cls < 11 ? class_names[cls] : "unknown";
  fail(path, ": dataset '", dataset, "' has unsupported type (", cname, ", ", size, " bytes", ")");
}

// Reads a dataset's raw bytes in its stored type; returns shape and type.
Opened read_raw(const std::string& path, const std::string& dataset, std::vector<uint8_t>& bytes) {
  silence_hdf5();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) fail(path, ": no such file");
  if (H5Fis_hdf5(path.c_str()) <= 0) fail(path, ": not an HDF5 file (bad or truncated superblock)");
  H5Id file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (file < 0) fail(path, ": cannot open HDF5 file (corrupt or truncated)");
  if (H5Lexists(file, dataset.c_str(), H5P_DEFAULT) <= 0) fail(path, ": no dataset named '", dataset, "'");
  H5Id dset(H5Dopen2(file, dataset.c_str(), H5P_DEFAULT), H5Dclose);
  if (dset < 0) fail(path, ": cannot open dataset '", dataset, "'");
  H5Id dtype(H5Dget_type(dset), H5Tclose);
  Opened out;
  out.type = classify(path, dataset, dtype);
  out.little_endian = H5Tget_order(dtype) != H5T_ORDER_BE;
  H5Id space(H5Dget_space(dset), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space);
  if (rank < 0) fail(path, ": dataset '", dataset, "' has an unreadable shape");
  std::vector<hsize_t> dims(rank);
  H5Sget_simple_extent_dims(space, dims.data(), nullptr);
  // Sizes come from the file: an empty extent or a declared 2^36 elements is refused here, before any
  // allocation, instead of failing later in OpenCV or in the allocator.
  const size_t elem = H5Tget_size(dtype);
  uint64_t count = 1;
  std::string shape_text;
  for (hsize_t d : dims) shape_text += (shape_text.empty() ? "" : "x") + std::to_string(d);
  for (hsize_t d : dims) {
    if (d == 0) fail(path, ": dataset '", dataset, "' is empty (shape [", shape_text, "])");
    if (__builtin_mul_overflow(count, static_cast<uint64_t>(d), &count) || count > kMaxHdf5Elements)
      fail(path, ": dataset '", dataset, "' declares shape [", shape_text, "], more than the ", kMaxHdf5Elements,
           " elements a dataset may hold here");
    out.shape.push_back(static_cast<int64_t>(d));
  }
  bytes.resize(count * elem);
  // Read in the stored type (no conversion): the memory type is the file type itself.
  if (count > 0 && H5Dread(dset, dtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, bytes.data()) < 0)
    fail(path, ": cannot read dataset '", dataset, "' (file truncated or corrupt)");
  if (!out.little_endian) {
    for (size_t i = 0; i < count; ++i) std::reverse(bytes.begin() + i * elem, bytes.begin() + (i + 1) * elem);
  }
  return out;
}

template <class Out>
void convert_from(const std::vector<uint8_t>& bytes, H5Type type, std::vector<Out>& out) {
  const size_t n = bytes.size() / (type == H5Type::Float16 || type == H5Type::Int16   ? 2
                                   : type == H5Type::UInt8                            ? 1
                                   : type == H5Type::Float32 || type == H5Type::Int32 ? 4
                                                                                      : 8);
  out.resize(n);
  auto copy = [&](auto tag) {
    using In = decltype(tag);
    const In* src = reinterpret_cast<const In*>(bytes.data());
    for (size_t i = 0; i < n; ++i) out[i] = static_cast<Out>(src[i]);
  };
  switch (type) {
    case H5Type::Float16: {
      const uint16_t* src = reinterpret_cast<const uint16_t*>(bytes.data());
      for (size_t i = 0; i < n; ++i) {
        Imath::half h;
        h.setBits(src[i]);
        out[i] = static_cast<Out>(static_cast<float>(h));
      }
      break;
    }
    case H5Type::Float32:
      copy(float{});
      break;
    case H5Type::Float64:
      copy(double{});
      break;
    case H5Type::Int16:
      copy(int16_t{});
      break;
    case H5Type::Int32:
      copy(int32_t{});
      break;
    case H5Type::Int64:
      copy(int64_t{});
      break;
    case H5Type::UInt8:
      copy(uint8_t{});
      break;
  }
}

bool is_float(H5Type t) {
  return t == H5Type::Float16 || t == H5Type::Float32 || t == H5Type::Float64;
}

template <class Out>
H5Array<Out> read_as(const std::string& path, const std::string& dataset, bool want_float) {
  std::lock_guard<std::mutex> lock(hdf5_mutex());
  std::vector<uint8_t> bytes;
  Opened o = read_raw(path, dataset, bytes);
  if (is_float(o.type) != want_float)
    fail(path, ": dataset '", dataset, "' has type ", h5type_name(o.type), "; expected ",
         want_float ? "a floating-point dataset (float16/float32/float64)" : "an integer dataset");
  H5Array<Out> out;
  out.shape = o.shape;
  out.stored = o.type;
  convert_from(bytes, o.type, out.values);
  return out;
}

template <class In>
void write_impl(const std::string& path, const std::vector<int64_t>& shape, const In* data, H5Type stored,
                int gzip_level, const std::string& dataset) {
  std::lock_guard<std::mutex> lock(hdf5_mutex());
  silence_hdf5();
  ISPLAT_CHECK(gzip_level >= 0 && gzip_level <= 9, path, ": gzip level must be 0..9, got ", gzip_level);
  size_t count = 1;
  std::vector<hsize_t> dims;
  for (int64_t d : shape) {
    ISPLAT_CHECK(d >= 0, path, ": negative dimension in shape");
    dims.push_back(static_cast<hsize_t>(d));
    count *= static_cast<size_t>(d);
  }
  // Convert in our code, then hand HDF5 bytes that already match the file type.
  std::vector<uint8_t> bytes;
  hid_t file_type = -1;
  bool own_type = false;
  auto store = [&](auto tag, hid_t t) {
    using T = decltype(tag);
    bytes.resize(count * sizeof(T));
    T* dst = reinterpret_cast<T*>(bytes.data());
    for (size_t i = 0; i < count; ++i) dst[i] = static_cast<T>(data[i]);
    file_type = t;
  };
  switch (stored) {
    case H5Type::Float16: {
      bytes.resize(count * 2);
      uint16_t* dst = reinterpret_cast<uint16_t*>(bytes.data());
      for (size_t i = 0; i < count; ++i) dst[i] = Imath::half(static_cast<float>(data[i])).bits();
      file_type = make_half_type();
      own_type = true;
      break;
    }
    case H5Type::Float32:
      store(float{}, H5T_IEEE_F32LE);
      break;
    case H5Type::Float64:
      store(double{}, H5T_IEEE_F64LE);
      break;
    case H5Type::Int16:
      store(int16_t{}, H5T_STD_I16LE);
      break;
    case H5Type::Int32:
      store(int32_t{}, H5T_STD_I32LE);
      break;
    case H5Type::Int64:
      store(int64_t{}, H5T_STD_I64LE);
      break;
    case H5Type::UInt8:
      store(uint8_t{}, H5T_STD_U8LE);
      break;
  }
  H5Id type_guard(own_type ? file_type : -1, H5Tclose);
  AtomicPath target(path);
  {
    H5Id file(H5Fcreate(target.temp().c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
    if (file < 0) fail(path, ": cannot create HDF5 file");
    H5Id space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose);
    H5Id dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    if (gzip_level > 0 && count > 0 && !dims.empty()) {
      std::vector<hsize_t> chunk = dims;
      const size_t row_bytes = bytes.size() / std::max<hsize_t>(1, dims[0]);
      chunk[0] = std::max<hsize_t>(1, std::min<hsize_t>(dims[0], (1u << 20) / std::max<size_t>(1, row_bytes)));
      H5Pset_chunk(dcpl, static_cast<int>(chunk.size()), chunk.data());
      H5Pset_deflate(dcpl, static_cast<unsigned>(gzip_level));
    }
    H5Id dset(H5Dcreate2(file, dataset.c_str(), file_type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT), H5Dclose);
    if (dset < 0) fail(path, ": cannot create dataset '", dataset, "'");
    if (count > 0 && H5Dwrite(dset, file_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, bytes.data()) < 0)
      fail(path, ": cannot write dataset '", dataset, "'");
  }
  target.commit();
}

}  // namespace

const char* h5type_name(H5Type t) {
  switch (t) {
    case H5Type::Float16:
      return "float16";
    case H5Type::Float32:
      return "float32";
    case H5Type::Float64:
      return "float64";
    case H5Type::Int16:
      return "int16";
    case H5Type::Int32:
      return "int32";
    case H5Type::Int64:
      return "int64";
    case H5Type::UInt8:
      return "uint8";
  }
  return "?";
}

template <class T>
int64_t H5Array<T>::numel() const {
  return std::accumulate(shape.begin(), shape.end(), int64_t{1}, std::multiplies<int64_t>());
}
template struct H5Array<float>;
template struct H5Array<double>;
template struct H5Array<int64_t>;

H5Array<float> read_hdf5_float(const std::string& path, const std::string& dataset) {
  return read_as<float>(path, dataset, true);
}
H5Array<double> read_hdf5_double(const std::string& path, const std::string& dataset) {
  return read_as<double>(path, dataset, true);
}
H5Array<int64_t> read_hdf5_int(const std::string& path, const std::string& dataset) {
  return read_as<int64_t>(path, dataset, false);
}

void write_hdf5(const std::string& path, const std::vector<int64_t>& shape, const float* data, H5Type stored,
                int gzip_level, const std::string& dataset) {
  write_impl(path, shape, data, stored, gzip_level, dataset);
}
void write_hdf5(const std::string& path, const std::vector<int64_t>& shape, const double* data, H5Type stored,
                int gzip_level, const std::string& dataset) {
  write_impl(path, shape, data, stored, gzip_level, dataset);
}
void write_hdf5(const std::string& path, const std::vector<int64_t>& shape, const int64_t* data, H5Type stored,
                int gzip_level, const std::string& dataset) {
  write_impl(path, shape, data, stored, gzip_level, dataset);
}

}  // namespace isplat
