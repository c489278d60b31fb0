// Stanford 3D Scanning Repository alignment files: "bmesh FILE tx ty tz qx qy qz qw" (or "mesh ...")
// per scan.
#include "shape/io/stanford_conf.h"

#include <cmath>
#include <map>
#include <string>

#include "shape/core/atomic_file.h"
#include "shape/core/error.h"
#include "shape/core/log.h"
#include "shape/io/mapped_file.h"
#include "shape/io/text_scan.h"

namespace pectus {

std::vector<ScanPose> ParseStanfordConf(std::string_view bytes, const std::string& name) {
  if (bytes.empty()) ThrowBadInput(name, "file is empty");
  std::vector<ScanPose> poses;
  std::map<std::string, std::int64_t> line_of;  // file -> line it was listed on
  text::LineReader lines(bytes);
  std::string_view line;
  while (lines.Next(&line)) {
    const auto fail = [&](const std::string& message) { ThrowBadInput(name, message, lines.number()); };
    std::string_view rest = line;
    const std::string_view keyword = text::NextToken(&rest);
    if (keyword.empty() || keyword.front() == '#') continue;
    if (keyword == "camera") continue;  // the viewpoint of the scanning program, not a pose
    if (keyword != "bmesh" && keyword != "mesh") {
      fail("unexpected '" + std::string(keyword.substr(0, 40)) + "' (expected 'bmesh', 'mesh' or 'camera')");
    }
    std::string_view fields[8];
    int count = 0;
    for (std::string_view token = text::NextToken(&rest); !token.empty(); token = text::NextToken(&rest)) {
      if (count < 8) fields[count] = token;
      ++count;
    }
    double unused;
    if (keyword == "mesh" && count == 7 && text::ParseDouble(fields[0], &unused)) {
      Info(name + ":" + std::to_string(lines.number()) + ": a 'mesh' line without a file, skipped");
      continue;
    }
    if (count != 8) {
      fail("expected 8 fields after '" + std::string(keyword) + "' (FILE tx ty tz qx qy qz qw), found " +
           std::to_string(count));
    }
    double v[7];
    for (int k = 0; k < 7; ++k) {
      const std::string_view token = fields[k + 1];
      if (!text::ParseDouble(token, &v[k]))
        fail("'" + std::string(token.substr(0, 40)) + "' is not a number");
      if (!std::isfinite(v[k])) fail("non-finite number '" + std::string(token) + "'");
    }
    const std::string file(fields[0]);
    if (const auto [it, inserted] = line_of.try_emplace(file, lines.number()); !inserted) {
      fail("'" + file + "' is listed twice (lines " + std::to_string(it->second) + " and " +
           std::to_string(lines.number()) + ")");
    }
    Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);  // (w, x, y, z)
    const double norm = q.norm();
    if (!(norm > 1e-12)) fail("quaternion (qx qy qz qw) is zero and names no rotation");
    q.coeffs() /= norm;
    // p_common = R(q)^T p_scan + t.
    ScanPose pose{file, Rigid3::Identity(), std::string(keyword)};
    pose.T_common_scan.linear() = q.toRotationMatrix().transpose();
    pose.T_common_scan.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
    poses.push_back(std::move(pose));
  }
  if (poses.empty()) ThrowBadInput(name, "no 'bmesh' or 'mesh' lines: not a Stanford .conf file?");
  return poses;
}

std::vector<ScanPose> ReadStanfordConf(const std::filesystem::path& path) {
  MappedFile file(path.string());
  std::vector<ScanPose> poses = ParseStanfordConf(file.bytes(), path.string());
  std::vector<ScanPose> kept;
  for (ScanPose& pose : poses) {
    std::error_code ec;
    if (pose.keyword == "mesh" && !std::filesystem::exists(path.parent_path() / pose.file, ec)) {
      Info(path.string() + ": 'mesh " + pose.file + "' skipped: no such file beside the .conf");
      continue;
    }
    kept.push_back(std::move(pose));
  }
  if (kept.empty()) ThrowBadInput(path.string(), "none of the scans its 'mesh' lines name is beside it");
  return kept;
}

void WriteStanfordConf(const std::filesystem::path& path, const std::vector<ScanPose>& poses) {
  std::string out;
  for (const ScanPose& pose : poses) {
    if (pose.file.empty() || pose.file.find_first_of(" \t\r\n") != std::string::npos) {
      ThrowUsage(path.string() + ": scan file name '" + pose.file +
                 "' is empty or holds blanks, which a .conf cannot store");
    }
    // R(q) = (linear part)^T; the quaternion of the transpose is the conjugate's.
    const Eigen::Quaterniond q(Eigen::Matrix3d(pose.T_common_scan.linear().transpose()));
    const Eigen::Vector3d t = pose.T_common_scan.translation();
    // Shortest text that reads back exactly (at most 17 significant digits), independent of the locale.
    out += (pose.keyword == "mesh" ? "mesh " : "bmesh ") + pose.file;
    for (double v : {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()}) {
      out += ' ';
      text::AppendNumber(v, &out);
    }
    out += '\n';
  }
  WriteFileAtomically(path, out);
}

void ScaleTranslations(double factor, std::vector<ScanPose>* poses) {
  for (ScanPose& pose : *poses) pose.T_common_scan.translation() *= factor;
}

}  // namespace pectus
