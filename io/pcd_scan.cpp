// SPDX-License-Identifier: BSD-3-Clause
#include "io/pcd_scan.hpp"

#include <algorithm>
#include <cerrno>

#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/pcd_header.hpp"

namespace lidarcal::io {
namespace {

namespace fs = std::filesystem;
using pcd::checkCoordinateField;
using pcd::findField;
using pcd::HeaderField;
using pcd::kFormatRemedy;
using pcd::kMaxAbsCoordinate_m;
using pcd::ParsedHeader;
using pcd::parseHeader;
using pcd::viewpointPose;

/// A scan file opened for reading (one open, one fstat), its bytes read as far as needed (a
/// stream's seeks and buffered reads cost more system calls than the file itself).
class PcdFile {
 public:
  explicit PcdFile(const fs::path& file);
  ~PcdFile() { ::close(fd_); }
  PcdFile(const PcdFile&) = delete;
  PcdFile& operator=(const PcdFile&) = delete;
  /// Reads on until the first min(n, size) bytes are in bytes().
  void readUpTo(std::size_t n);
  const std::string& bytes() const { return bytes_; }
  std::size_t size() const { return size_; }

 private:
  std::string where_;
  int fd_ = -1;
  std::size_t size_ = 0;
  std::string bytes_;
};

/// A stream over a PcdFile that reads on from the file as it is consumed (parsing a header reads
/// the header, not the data behind it), seekable within the file for PCL's ASCII body reader.
class PcdStreamBuffer : public std::streambuf {
 public:
  explicit PcdStreamBuffer(PcdFile& file) : file_(file) { point(0); }

 protected:
  int_type underflow() override {
    const std::size_t at = static_cast<std::size_t>(gptr() - eback());
    if (at >= file_.bytes().size()) file_.readUpTo(at + kChunk);
    point(at);
    return at < file_.bytes().size() ? traits_type::to_int_type(file_.bytes()[at])
                                     : traits_type::eof();
  }
  pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode) override {
    const off_type base = dir == std::ios_base::beg   ? 0
                          : dir == std::ios_base::cur ? gptr() - eback()
                                                      : static_cast<off_type>(file_.size());
    return seekpos(pos_type(base + off), std::ios_base::in);
  }
  pos_type seekpos(pos_type pos, std::ios_base::openmode) override {
    if (pos < 0 || static_cast<std::size_t>(pos) > file_.size()) return pos_type(off_type(-1));
    file_.readUpTo(static_cast<std::size_t>(pos));
    point(static_cast<std::size_t>(pos));
    return pos;
  }

 private:
  static constexpr std::size_t kChunk = 4096;
  /// The get area over the bytes read so far (the string may have moved), positioned at `at`.
  void point(std::size_t at) {
    char* p = const_cast<char*>(file_.bytes().data());  // only read: no put area
    setg(p, p + at, p + file_.bytes().size());
  }
  PcdFile& file_;
};

/// A directory where a scan file is expected: name one of its scans.
[[noreturn]] void refuseDirectory(const fs::path& file) {
  std::error_code ec;
  fs::path example = file / "scan_000000.pcd";
  std::vector<fs::path> pcds;
  for (const auto& e : fs::directory_iterator(file, ec))
    if (e.path().extension() == ".pcd") pcds.push_back(e.path());
  if (!pcds.empty()) example = *std::min_element(pcds.begin(), pcds.end());
  throw InputError(file.string(), "",
                   "is a directory; give a .pcd file (e.g. " + example.string() + ")",
                   "commands that read a whole sequence (info, detect, calibrate, correct, run) "
                   "take the directory");
}

PcdFile::PcdFile(const fs::path& file) : where_(file.string()) {
  fd_ = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) {
    if (errno == ENOENT) throw InputError(where_, "", "file does not exist", "check the path");
    throw InputError(where_, "", "cannot be opened for reading", "check its permissions");
  }
  struct stat st {};
  const bool stated = ::fstat(fd_, &st) == 0;
  if (!stated || !S_ISREG(st.st_mode)) {
    ::close(fd_);
    if (stated && S_ISDIR(st.st_mode)) refuseDirectory(file);
    throw InputError(where_, "", "cannot be read (not a regular file)",
                     "give the path of a .pcd file");
  }
  size_ = static_cast<std::size_t>(st.st_size);
}

void PcdFile::readUpTo(std::size_t n) {
  const std::size_t want = std::min(n, size_);
  std::size_t got = bytes_.size();
  if (got >= want) return;
  bytes_.resize(want);
  while (got < want) {
    const ssize_t r = ::read(fd_, bytes_.data() + got, want - got);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) break;
    got += static_cast<std::size_t>(r);
  }
  if (got < want)
    throw InputError(where_, "DATA",
                     "could not be read to its end (the file changed or the disk failed)",
                     "run again");
}

/// binary_compressed data starts with the compressed and the uncompressed size (uint32 each).
/// PCL trusts the uncompressed size when unpacking: it must be what the header promises, and
/// the compressed block must lie within the file.
void checkCompressedBlock(const std::string& where, const ParsedHeader& h, std::size_t promised,
                          std::size_t data_bytes, const std::string& bytes) {
  std::uint32_t sizes[2] = {0, 0};
  if (data_bytes < 8 || h.data_offset + sizeof sizes > bytes.size())
    throw InputError(where, "DATA", "file is truncated: no compressed block after the header",
                     "the recording was cut short; re-export or drop this file");
  std::memcpy(sizes, bytes.data() + h.data_offset, sizeof sizes);
  if (sizes[1] != promised)
    throw InputError(where, "DATA",
                     "the compressed block unpacks to " + std::to_string(sizes[1]) +
                         " bytes, the header promises " + std::to_string(promised) +
                         " (damaged file)",
                     "re-export the scan");
  if (sizes[0] > data_bytes - 8)
    throw InputError(where, "DATA",
                     "file is truncated: the compressed block has " + std::to_string(sizes[0]) +
                         " bytes, the file holds " + std::to_string(data_bytes - 8),
                     "the recording was cut short; re-export or drop this file");
}

/// The checked header of `file` (`file_size` bytes, `bytes` its first ones: the compressed block's
/// sizes).
ScanHeader toScanHeader(const fs::path& file, const ParsedHeader& h, std::size_t file_size,
                        const std::string& bytes) {
  const std::string where = file.string();
  checkCoordinateField(h, "x", true, where);
  checkCoordinateField(h, "y", true, where);
  checkCoordinateField(h, "z", false, where);
  if (h.height > 1)
    throw InputError(
        where, "HEIGHT",
        "this is a 3D organised cloud (" + std::to_string(h.width) + "x" +
            std::to_string(h.height) +
            " points), not a 2D lidar scan; lidarcal's 2D commands need one planar scan per file "
            "(HEIGHT 1, the sensor's pose in VIEWPOINT, docs/FORMAT.md)",
        "import a 2D lidar recording with lidarcal import; for cylinders in a 3D cloud use the "
        "library "
        "function lidarcal::detectors::detectCylinder (detectors/cylinder.hpp, PCL's cylinder "
        "segmentation)");
  ScanHeader out;
  out.path = file.string();
  out.viewpoint = viewpointPose(h, where);
  out.points = static_cast<std::size_t>(h.points);
  out.has_intensity = findField(h, "intensity") != nullptr;
  out.has_label = findField(h, "label") != nullptr;
  out.binary = h.data != "ascii";
  // The data must be able to hold what the header promises, before PCL allocates for it: binary
  // data is point_bytes per point; ASCII needs at least two characters per value ("0 "); LZF
  // (binary_compressed) expands at most about 100-fold (a 3-byte back reference yields up to
  // 264 bytes).
  std::size_t point_bytes = 0, values = 0;
  for (const auto& f : h.fields) {
    point_bytes += static_cast<std::size_t>(f.size) * static_cast<std::size_t>(f.count);
    values += static_cast<std::size_t>(f.count);
  }
  {
    const std::size_t data_bytes = file_size > h.data_offset ? file_size - h.data_offset : 0;
    const double promised = static_cast<double>(point_bytes) * static_cast<double>(out.points);
    if (h.data == "binary" && file_size < h.data_offset + point_bytes * out.points)
      throw InputError(where, "DATA",
                       "file is truncated: " + std::to_string(file_size) +
                           " bytes, the header promises " +
                           std::to_string(h.data_offset + point_bytes * out.points),
                       "the recording was cut short; re-export or drop this file");
    if (h.data == "binary_compressed" && out.points > 0)
      checkCompressedBlock(where, h, point_bytes * out.points, data_bytes, bytes);
    if ((h.data == "ascii" &&
         2.0 * static_cast<double>(values) * static_cast<double>(out.points) > data_bytes + 1.0) ||
        (h.data == "binary_compressed" &&
         promised > 300.0 * static_cast<double>(data_bytes) + 4096.0))
      throw InputError(where, "DATA",
                       "file is truncated: " + std::to_string(data_bytes) +
                           " bytes of data cannot hold the " + std::to_string(out.points) +
                           " points the header promises",
                       "the recording was cut short; re-export or drop this file");
  }
  return out;
}

/// Value of element 0 of a field as double.
double readValue(const std::uint8_t* p, std::uint8_t datatype) {
  switch (datatype) {
    case pcl::PCLPointField::INT8: {
      std::int8_t v;
      std::memcpy(&v, p, 1);
      return v;
    }
    case pcl::PCLPointField::UINT8: {
      std::uint8_t v;
      std::memcpy(&v, p, 1);
      return v;
    }
    case pcl::PCLPointField::INT16: {
      std::int16_t v;
      std::memcpy(&v, p, 2);
      return v;
    }
    case pcl::PCLPointField::UINT16: {
      std::uint16_t v;
      std::memcpy(&v, p, 2);
      return v;
    }
    case pcl::PCLPointField::INT32: {
      std::int32_t v;
      std::memcpy(&v, p, 4);
      return v;
    }
    case pcl::PCLPointField::UINT32: {
      std::uint32_t v;
      std::memcpy(&v, p, 4);
      return v;
    }
    case pcl::PCLPointField::FLOAT32: {
      float v;
      std::memcpy(&v, p, 4);
      return v;
    }
    case pcl::PCLPointField::FLOAT64: {
      double v;
      std::memcpy(&v, p, 8);
      return v;
    }
    default:
      return std::numeric_limits<double>::quiet_NaN();
  }
}

const pcl::PCLPointField* cloudField(const pcl::PCLPointCloud2& cloud, const std::string& name) {
  for (const auto& f : cloud.fields)
    if (f.name == name) return &f;
  return nullptr;
}

void appendField(pcl::PCLPointCloud2& cloud, const std::string& name, std::uint8_t datatype,
                 std::uint32_t size) {
  pcl::PCLPointField f;
  f.name = name;
  f.offset = cloud.point_step;
  f.datatype = datatype;
  f.count = 1;
  cloud.fields.push_back(f);
  cloud.point_step += size;
}

}  // namespace

void yawToQuaternion(double yaw_rad, double& qw, double& qz) {
  qw = std::cos(0.5 * yaw_rad);
  qz = std::sin(0.5 * yaw_rad);
}

ScanHeader readScanHeader(const fs::path& file) {
  PcdFile f(file);
  PcdStreamBuffer buffer(f);
  std::istream in(&buffer);
  const ParsedHeader h = parseHeader(in, file.string());
  f.readUpTo(h.data_offset + 8);  // a compressed block's sizes
  return toScanHeader(file, h, f.size(), f.bytes());
}

namespace {

/// PCL's datatype for a checked header field (TYPE F/I/U, SIZE 1/2/4/8), as PCL's header reader
/// maps them.
std::uint8_t datatypeOf(const HeaderField& f) {
  using P = pcl::PCLPointField;
  switch (f.type) {
    case 'F':
      return f.size == 8 ? P::FLOAT64 : P::FLOAT32;
    case 'I':
      return f.size == 1 ? P::INT8 : f.size == 2 ? P::INT16 : f.size == 4 ? P::INT32 : P::INT64;
    default:
      return f.size == 1 ? P::UINT8 : f.size == 2 ? P::UINT16 : f.size == 4 ? P::UINT32 : P::UINT64;
  }
}

/// The blob's layout from the checked header (what PCL's readHeader would set up: fields at
/// packed offsets, the data sized for every point), so that PCL's body reader can fill it
/// without parsing the header a second time.
pcl::PCLPointCloud2 blobLayout(const ParsedHeader& h) {
  pcl::PCLPointCloud2 blob;
  std::uint32_t offset = 0;
  for (const auto& f : h.fields) {
    pcl::PCLPointField pf;
    pf.name = f.name;
    pf.offset = offset;
    pf.datatype = datatypeOf(f);
    pf.count = static_cast<std::uint32_t>(f.count);
    blob.fields.push_back(pf);
    offset += static_cast<std::uint32_t>(f.size * f.count);
  }
  blob.point_step = offset;
  blob.width = static_cast<std::uint32_t>(h.width);
  blob.height = static_cast<std::uint32_t>(h.height);
  blob.row_step = blob.point_step * blob.width;
  blob.data.resize(static_cast<std::size_t>(blob.row_step) * blob.height);
  return blob;
}

/// The size of a binary_compressed block (its first uint32, at byte `at`); 0 when the bytes end
/// before it.
std::size_t compressedBlockSize(const std::string& bytes, std::size_t at) {
  std::uint32_t size = 0;
  if (bytes.size() >= at + 8) std::memcpy(&size, bytes.data() + at, sizeof size);
  return size;
}

/// The point data of a checked file, read by PCL's body reader from the file's bytes in memory
/// (the file is opened once: header, checks and data; the header parsed once, by parseHeader).
pcl::PCLPointCloud2 readBlob(PcdFile& f, const ParsedHeader& h, const std::string& where) {
  pcl::PCLPointCloud2 blob = blobLayout(h);
  const auto data_idx = static_cast<unsigned int>(h.data_offset);
  pcl::PCDReader reader;
  int rc = 0;
  if (h.data == "ascii") {
    PcdStreamBuffer buffer(f);
    std::istream stream(&buffer);
    stream.seekg(static_cast<std::streamoff>(data_idx));
    rc = reader.readBodyASCII(stream, blob, pcl::PCDReader::PCD_V7);
  } else {
    const bool compressed = h.data == "binary_compressed";
    if (compressed && blob.data.empty()) return blob;  // no points: no block to unpack
    // How far the data goes: the packed points, or the compressed block's sizes and bytes (the
    // caller read the sizes). PCL's body reader takes no length, so the bytes must reach there.
    const std::size_t end = compressed ? data_idx + 8 + compressedBlockSize(f.bytes(), data_idx)
                                       : data_idx + blob.data.size();
    f.readUpTo(end);
    if (end > f.bytes().size()) rc = -1;
    if (rc == 0)
      rc = reader.readBodyBinary(reinterpret_cast<const unsigned char*>(f.bytes().data()), blob,
                                 pcl::PCDReader::PCD_V7, compressed, data_idx);
  }
  if (rc < 0)
    throw InputError(where, "DATA", "PCL could not read the point data (truncated or garbled file)",
                     "re-export the scan; the header is valid but the data is not");
  return blob;
}

/// The fields of a scan cloud (x and y required; the rest may be null).
struct ScanFields {
  const pcl::PCLPointField *x, *y, *z, *intensity, *label, *correction, *correction_se;
};

ScanFields scanFields(const pcl::PCLPointCloud2& blob, const std::string& where) {
  const ScanFields f{cloudField(blob, "x"),
                     cloudField(blob, "y"),
                     cloudField(blob, "z"),
                     cloudField(blob, "intensity"),
                     cloudField(blob, "label"),
                     cloudField(blob, "correction"),
                     cloudField(blob, "correction_se")};
  if (!f.x || !f.y)  // the header we checked has them; PCL must have read the same header
    throw InputError(where, "FIELDS",
                     "PCL read other fields than the header lists (a damaged file)",
                     "re-export the scan");
  return f;
}

/// A point's coordinates as a reading can have them: both NaN (no return) or finite and within
/// 100 km.
void checkCoordinates(double x, double y, double z, const std::string& where, std::size_t i) {
  const auto item = [i] { return "point " + std::to_string(i); };
  const bool nan_x = std::isnan(x), nan_y = std::isnan(y);
  if (nan_x != nan_y)
    throw InputError(where, item(),
                     "only one of x, y is NaN: a beam without return must have x and y NaN",
                     kFormatRemedy);
  if (nan_x) return;
  if (!std::isfinite(x) || !std::isfinite(y) || (!std::isnan(z) && !std::isfinite(z)))
    throw InputError(where, item(), "coordinate is infinite",
                     "write NaN for a beam with no return");
  if (std::abs(x) > kMaxAbsCoordinate_m || std::abs(y) > kMaxAbsCoordinate_m ||
      (!std::isnan(z) && std::abs(z) > kMaxAbsCoordinate_m))
    throw InputError(where, item(), "coordinate beyond 100 km: not a lidar reading",
                     "check the units (metres) or write NaN for a beam with no return");
}

/// Point i's label and correction, when the cloud has them.
void readPointExtras(const std::uint8_t* p, const ScanFields& f, std::size_t i,
                     const std::string& where, Scan& scan) {
  if (f.label) {
    const double label = readValue(p + f.label->offset, f.label->datatype);
    if (!(label >= 0.0) || label > 4294967295.0)
      throw InputError(where, "point " + std::to_string(i), "label is not a non-negative integer",
                       kFormatRemedy);
    scan.labels[i] = static_cast<std::uint32_t>(label);
  }
  if (f.correction) {
    const double code = readValue(p + f.correction->offset, f.correction->datatype);
    if (!(code >= 0.0 && code <= 3.0) || code != std::floor(code))
      throw InputError(where, "point " + std::to_string(i), "correction is not 0, 1, 2 or 3",
                       kFormatRemedy);
    scan.correction[i] = static_cast<PointCorrection>(static_cast<std::uint8_t>(code));
    if (f.correction_se)
      scan.correction_se[i] =
          static_cast<float>(readValue(p + f.correction_se->offset, f.correction_se->datatype));
  }
}

}  // namespace

Scan readScan(const fs::path& file) {
  const std::string where = file.string();
  PcdFile f(file);
  ParsedHeader parsed;
  {
    PcdStreamBuffer buffer(f);
    std::istream in(&buffer);
    parsed = parseHeader(in, where);
  }
  f.readUpTo(parsed.data_offset + 8);  // a compressed block's sizes
  const ScanHeader header = toScanHeader(file, parsed, f.size(), f.bytes());
  const pcl::PCLPointCloud2 blob = readBlob(f, parsed, where);
  const std::size_t n = static_cast<std::size_t>(blob.width) * blob.height;
  if (n != header.points || blob.data.size() < n * blob.point_step)
    throw InputError(where, "DATA", "holds fewer points than the header's POINTS",
                     "re-export the scan");
  const ScanFields fields = scanFields(blob, where);

  Scan scan;
  scan.name = file.filename().string();
  scan.viewpoint = header.viewpoint;
  scan.has_intensity = fields.intensity != nullptr;
  scan.cloud.reset(new pcl::PointCloud<pcl::PointXYZI>);
  scan.cloud->resize(n);
  scan.cloud->width = static_cast<std::uint32_t>(n);
  scan.cloud->height = 1;
  scan.cloud->is_dense = true;
  if (fields.label) scan.labels.resize(n);
  if (fields.correction) scan.correction.resize(n);
  if (fields.correction && fields.correction_se) scan.correction_se.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* p = blob.data.data() + i * blob.point_step;
    const double x = readValue(p + fields.x->offset, fields.x->datatype);
    const double y = readValue(p + fields.y->offset, fields.y->datatype);
    const double z = fields.z ? readValue(p + fields.z->offset, fields.z->datatype) : 0.0;
    checkCoordinates(x, y, z, where, i);
    const bool no_return = std::isnan(x);
    if (no_return) scan.cloud->is_dense = false;
    auto& pt = (*scan.cloud)[i];
    pt.x = static_cast<float>(x);
    pt.y = static_cast<float>(y);
    pt.z = no_return ? std::numeric_limits<float>::quiet_NaN()
                     : static_cast<float>(std::isnan(z) ? 0.0 : z);
    pt.intensity = fields.intensity ? static_cast<float>(readValue(p + fields.intensity->offset,
                                                                   fields.intensity->datatype))
                                    : 0.0f;
    readPointExtras(p, fields, i, where, scan);
  }
  return scan;
}

void writeScan(const fs::path& file, const Scan& scan, PcdEncoding encoding) {
  if (!scan.cloud) throw std::invalid_argument("writeScan: scan has no cloud");
  const std::size_t n = scan.cloud->size();
  if (!scan.labels.empty() && scan.labels.size() != n)
    throw std::invalid_argument("writeScan: labels and points differ in number");
  const bool corrections = !scan.correction.empty();
  if (corrections && (scan.correction.size() != n || scan.correction_se.size() != n))
    throw std::invalid_argument("writeScan: corrections and points differ in number");

  // Packed fields, no padding: x y z [intensity] [label] [correction correction_se].
  pcl::PCLPointCloud2 blob;
  appendField(blob, "x", pcl::PCLPointField::FLOAT32, 4);
  appendField(blob, "y", pcl::PCLPointField::FLOAT32, 4);
  appendField(blob, "z", pcl::PCLPointField::FLOAT32, 4);
  if (scan.has_intensity) appendField(blob, "intensity", pcl::PCLPointField::FLOAT32, 4);
  if (!scan.labels.empty()) appendField(blob, "label", pcl::PCLPointField::UINT32, 4);
  if (corrections) {
    appendField(blob, "correction", pcl::PCLPointField::UINT8, 1);
    appendField(blob, "correction_se", pcl::PCLPointField::FLOAT32, 4);
  }
  blob.width = static_cast<std::uint32_t>(n);
  blob.height = 1;
  blob.row_step = blob.point_step * blob.width;
  blob.is_dense = true;
  blob.data.resize(static_cast<std::size_t>(blob.row_step));
  for (std::size_t i = 0; i < n; ++i) {
    const auto& pt = (*scan.cloud)[i];
    std::uint8_t* p = blob.data.data() + i * blob.point_step;
    std::memcpy(p + 0, &pt.x, 4);
    std::memcpy(p + 4, &pt.y, 4);
    std::memcpy(p + 8, &pt.z, 4);
    std::size_t off = 12;
    if (scan.has_intensity) {
      std::memcpy(p + off, &pt.intensity, 4);
      off += 4;
    }
    if (!scan.labels.empty()) {
      std::memcpy(p + off, &scan.labels[i], 4);
      off += 4;
    }
    if (corrections) {
      p[off] = static_cast<std::uint8_t>(scan.correction[i]);
      std::memcpy(p + off + 1, &scan.correction_se[i], 4);
    }
    if (!std::isfinite(pt.x)) blob.is_dense = false;
  }

  double qw = 1.0, qz = 0.0;
  yawToQuaternion(scan.viewpoint.yaw_rad, qw, qz);
  const Eigen::Vector4f origin(static_cast<float>(scan.viewpoint.x_m),
                               static_cast<float>(scan.viewpoint.y_m), 0.0f, 0.0f);
  const Eigen::Quaternionf orientation(static_cast<float>(qw), 0.0f, 0.0f, static_cast<float>(qz));

  writeAtomically(file, [&](const fs::path& tmp) {
    pcl::PCDWriter writer;
    bool ok = true;
    if (encoding == PcdEncoding::binary) {
      // PCL's header followed by the packed data: the bytes of PCL's writeBinary without the
      // page of padding it stretches the file by, in one open and one write.
      const std::string header =
          writer.generateHeaderBinary(blob, origin, orientation) + "DATA binary\n";
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      out.write(header.data(), static_cast<std::streamsize>(header.size()));
      out.write(reinterpret_cast<const char*>(blob.data.data()),
                static_cast<std::streamsize>(blob.data.size()));
      out.close();
      ok = !out.fail();
    } else {
      ok = writer.writeASCII(tmp.string(), blob, origin, orientation, 9) == 0;
    }
    if (!ok)
      throw InputError(file.string(), "", "could not write the PCD file (disk full?)",
                       "free some space and check permissions, then run again");
  });
}

}  // namespace lidarcal::io
