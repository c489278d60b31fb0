#include "shape/io/csv_writer.h"

#include <sstream>

#include "shape/core/atomic_file.h"
#include "shape/core/error.h"

namespace pectus {

std::string CsvText(const std::vector<std::string>& header, const Eigen::MatrixXd& values,
                    const std::vector<std::string>& row_names) {
  const bool named = !row_names.empty();
  if (named && row_names.size() != static_cast<std::size_t>(values.rows())) {
    ThrowUsage("CSV table: " + std::to_string(row_names.size()) + " row names for " +
               std::to_string(values.rows()) + " rows");
  }
  if (header.size() != static_cast<std::size_t>(values.cols()) + (named ? 1 : 0)) {
    ThrowUsage("CSV table: " + std::to_string(header.size()) + " column names for " +
               std::to_string(values.cols()) + " columns" + (named ? " and the row names" : ""));
  }
  std::ostringstream out;
  out.precision(10);
  for (std::size_t c = 0; c < header.size(); ++c) out << (c ? "," : "") << header[c];
  out << '\n';
  for (Eigen::Index r = 0; r < values.rows(); ++r) {
    if (named) out << row_names[static_cast<std::size_t>(r)];
    for (Eigen::Index c = 0; c < values.cols(); ++c) out << (c || named ? "," : "") << values(r, c);
    out << '\n';
  }
  return out.str();
}

void WriteCsv(const std::filesystem::path& path, const std::vector<std::string>& header,
              const Eigen::MatrixXd& values, const std::vector<std::string>& row_names) {
  WriteFileAtomically(path, CsvText(header, values, row_names));
}

}  // namespace pectus
