#include "pdamp/vtk/vtk_xml.hpp"

#include <bit>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <optional>
#include <sstream>
#include <type_traits>
#include <utility>

#include "pdamp/errors.hpp"

namespace pdamp::vtk {
namespace {

static_assert(std::endian::native == std::endian::little, "the files declare byte_order=\"LittleEndian\"");

/// The shortest text that reads back as the same double.
std::string exact(double value) {
  char text[32];
  const auto [end, ec] = std::to_chars(text, text + sizeof text, value);
  return std::string(text, end);
}

/// A file written with C stdio, whose errors name the file and the system's reason.
class OutputFile {
 public:
  OutputFile(const std::filesystem::path& file, const char* mode) : path_(file), file_(std::fopen(file.c_str(), mode)) {
    if (!file_) fail("cannot be opened for writing");
  }
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;
  ~OutputFile() {
    if (file_) std::fclose(file_);
  }

  void write(const void* bytes, std::size_t size) {
    if (size > 0 && std::fwrite(bytes, 1, size, file_) != size) fail("could not be written");
  }
  void write(const std::string& text) { write(text.data(), text.size()); }
  void seek_from_end(long offset) {
    if (std::fseek(file_, offset, SEEK_END) != 0) fail("could not be written");
  }
  void close() {
    std::FILE* file = file_;
    file_ = nullptr;
    if (std::fclose(file) != 0) fail("could not be written");
  }

 private:
  [[noreturn]] void fail(const char* what) const {
    throw RuntimeFailure("snapshot file '" + path_.string() + "' " + what + ": " + std::strerror(errno));
  }

  std::filesystem::path path_;
  std::FILE* file_;
};

/// The appended block of one array: its byte count, then its bytes.
struct Block {
  const void* bytes;
  std::uint64_t size;
};

template <class T>
Block block_of(const std::vector<T>& values) {
  return {values.data(), values.size() * sizeof(T)};
}

/// Lays out the header's array elements and the blocks they refer to, in order.
class AppendedData {
 public:
  /// The element of an array whose values are in `block`; field data say their tuples.
  std::string element(const std::string& type, const std::string& name, int components, Block block,
                      std::optional<std::size_t> tuples = std::nullopt) {
    std::ostringstream e;
    e << "<DataArray type=\"" << type << "\"";
    if (!name.empty()) e << " Name=\"" << name << "\"";
    if (components > 1) e << " NumberOfComponents=\"" << components << "\"";
    if (tuples) e << " NumberOfTuples=\"" << *tuples << "\"";
    e << " format=\"appended\" offset=\"" << offset_ << "\"/>\n";
    offset_ += sizeof(std::uint64_t) + block.size;
    blocks_.push_back(block);
    return e.str();
  }
  std::string element(const DataArray& a, bool with_tuples = false) {
    return std::visit(
        [&](const auto& values) {
          using T = typename std::decay_t<decltype(values)>::value_type;
          const std::size_t tuples = values.size() / static_cast<std::size_t>(a.components);
          return element(std::is_same_v<T, double> ? "Float64" : "Int64", a.name, a.components, block_of(values),
                         with_tuples ? std::optional(tuples) : std::nullopt);
        },
        a.values);
  }
  void write(OutputFile& out) const {
    out.write("  <AppendedData encoding=\"raw\">\n   _");
    for (const Block& b : blocks_) {
      out.write(&b.size, sizeof b.size);
      out.write(b.bytes, b.size);
    }
    out.write("\n  </AppendedData>\n</VTKFile>\n");
  }

 private:
  std::uint64_t offset_ = 0;
  std::vector<Block> blocks_;
};

constexpr const char* collection_end = "  </Collection>\n</VTKFile>\n";

std::string entry(const Collection::DataSet& d) {
  return "    <DataSet timestep=\"" + exact(d.time_s) + "\" part=\"" + std::to_string(d.part) + "\" file=\"" +
         d.relative_file + "\"/>\n";
}

}  // namespace

void write_poly_data(const std::filesystem::path& file, const PolyData& data) {
  AppendedData appended;
  std::ostringstream head;
  const std::size_t points = data.points.size() / 3;
  head << "<?xml version=\"1.0\"?>\n"
       << "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
       << "  <PolyData>\n";
  if (!data.field_data.empty()) {
    head << "    <FieldData>\n";
    for (const DataArray& a : data.field_data) head << "      " << appended.element(a, true);
    head << "    </FieldData>\n";
  }
  head << "    <Piece NumberOfPoints=\"" << points << "\" NumberOfVerts=\"" << data.verts.offsets.size()
       << "\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"" << data.polys.offsets.size() << "\">\n"
       << "      <PointData>\n";
  for (const DataArray& a : data.point_data) head << "        " << appended.element(a);
  head << "      </PointData>\n      <Points>\n        " << appended.element("Float64", "", 3, block_of(data.points))
       << "      </Points>\n";
  for (const auto& [tag, cells] : {std::pair{"Verts", &data.verts}, std::pair{"Polys", &data.polys}}) {
    head << "      <" << tag << ">\n        "
         << appended.element("Int64", "connectivity", 1, block_of(cells->connectivity)) << "        "
         << appended.element("Int64", "offsets", 1, block_of(cells->offsets)) << "      </" << tag << ">\n";
  }
  head << "    </Piece>\n  </PolyData>\n";
  OutputFile out(file, "wb");
  out.write(head.str());
  appended.write(out);
  out.close();
}

Collection::Collection(std::filesystem::path file, const std::vector<DataSet>& data_sets) : file_(std::move(file)) {
  std::string text = std::string("<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" ") +
                     "byte_order=\"LittleEndian\">\n  <Collection>\n";
  for (const DataSet& d : data_sets) text += entry(d);
  OutputFile out(file_, "wb");
  out.write(text + collection_end);
  out.close();
}

void Collection::add(const DataSet& data_set) {
  // Over the closing tags, which follow again: the file stays complete.
  OutputFile out(file_, "r+b");
  out.seek_from_end(-static_cast<long>(std::strlen(collection_end)));
  out.write(entry(data_set) + collection_end);
  out.close();
}

}  // namespace pdamp::vtk
