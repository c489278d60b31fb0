// pectus: CSV tables of numbers (model scores, eigenvalues, quality curves), written one way everywhere.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

namespace pectus {

/// The text of a CSV table: the header line, then one line per row of `values`, each led by its row name
/// when `row_names` is given (the header then names that column too). Numbers with 10 significant digits.
/// Throws Error(kUsage) if `row_names` is given and its size is not values.rows(), or if the header's
/// length is not values.cols() (+ 1 with row names).
/// @param[in] header     column names
/// @param[in] values     #rows by #columns
/// @param[in] row_names  empty, or one name per row (no comma or quote in a name)
std::string CsvText(const std::vector<std::string>& header, const Eigen::MatrixXd& values,
                    const std::vector<std::string>& row_names = {});

/// Writes CsvText(header, values, row_names) to `path` atomically (a temporary file renamed into place).
/// Throws as CsvText, and Error(kFailure) naming the file if it cannot be written.
void WriteCsv(const std::filesystem::path& path, const std::vector<std::string>& header,
              const Eigen::MatrixXd& values, const std::vector<std::string>& row_names = {});

}  // namespace pectus
