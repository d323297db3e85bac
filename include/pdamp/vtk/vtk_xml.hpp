#pragma once
/// The two VTK XML files a snapshot needs, written directly (docs/snapshots.md says why
/// not with VTK's library): PolyData (.vtp) with its arrays appended as raw little-endian
/// bytes, each behind a UInt64 byte count, and the ParaView data collection (.pvd) that
/// lists them as a time series.

#include <cstdint>
#include <filesystem>
#include <string>
#include <variant>
#include <vector>

namespace pdamp::vtk {

/// One array: `components` numbers per point (or per data set, for field data).
struct DataArray {
  std::string name;
  int components = 1;
  std::variant<std::vector<double>, std::vector<std::int64_t>> values;  ///< Float64 or Int64
};

/// Cells as VTK lists them: the point indices of every cell one after another, and the
/// end of each cell in that list.
struct CellList {
  std::vector<std::int64_t> connectivity;
  std::vector<std::int64_t> offsets;
};

struct PolyData {
  std::vector<double> points;  ///< x, y, z of each point
  CellList verts;              ///< one-point cells: what ParaView draws of bare points
  CellList polys;              ///< polygons
  std::vector<DataArray> point_data;
  std::vector<DataArray> field_data;  ///< about the whole data set (e.g. TimeValue)
};

/// Writes `data` to `file` (replacing it). Throws RuntimeFailure naming the file if it
/// cannot be written whole.
void write_poly_data(const std::filesystem::path& file, const PolyData& data);

/// A ParaView data collection (.pvd): data sets by time step and part, each file named
/// relative to the collection. The file is complete after every add(): a run stopped
/// halfway leaves a collection of the frames it wrote.
class Collection {
 public:
  /// A data set of part `part` at time `time_s`.
  struct DataSet {
    double time_s;
    int part;
    std::string relative_file;
  };

  /// Creates `file` (replacing it) listing `data_sets` (a resumed run's frames so far).
  explicit Collection(std::filesystem::path file, const std::vector<DataSet>& data_sets = {});

  void add(const DataSet& data_set);

  const std::filesystem::path& file() const { return file_; }

 private:
  std::filesystem::path file_;
};

}  // namespace pdamp::vtk
