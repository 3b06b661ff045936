// HDF5 datasets (float16/32/64, int16/32/64, uint8; gzip) through libhdf5's C API.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace isplat {

enum class H5Type { Float16, Float32, Float64, Int16, Int32, Int64, UInt8 };
const char* h5type_name(H5Type t);

template <class T>
struct H5Array {
  std::vector<int64_t> shape;
  std::vector<T> values;  // row-major
  H5Type stored = H5Type::Float32;
  int64_t numel() const;
};

// Floating-point datasets (float16/32/64) as float32. float16 is read raw and converted with
// Imath::half (HDF5 1.10 has no native half). Other stored types throw Error naming the type.
H5Array<float> read_hdf5_float(const std::string& path, const std::string& dataset = "dataset");
// Floating-point datasets as float64 (for poses and metadata).
H5Array<double> read_hdf5_double(const std::string& path, const std::string& dataset = "dataset");
// Integer datasets (int16/32/64, uint8) as int64.
H5Array<int64_t> read_hdf5_int(const std::string& path, const std::string& dataset = "dataset");

// Writes a dataset, converting to `stored` ourselves (HDF5's own float32->float16 conversion is wrong
// near powers of two: 3.9999998 -> 2.0). gzip_level 0 disables compression. Atomic.
void write_hdf5(const std::string& path, const std::vector<int64_t>& shape, const float* data, H5Type stored,
                int gzip_level = 4, const std::string& dataset = "dataset");
void write_hdf5(const std::string& path, const std::vector<int64_t>& shape, const double* data, H5Type stored,
                int gzip_level = 4, const std::string& dataset = "dataset");
void write_hdf5(const std::string& path, const std::vector<int64_t>& shape, const int64_t* data, H5Type stored,
                int gzip_level = 4, const std::string& dataset = "dataset");

}  // namespace isplat
