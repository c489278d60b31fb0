// pectus model build|info|modes|evaluate|project: the average chest and its principal modes from resampled
// grids (dissertation §4.3.1, Eqs. 13-14), stored as a statismo HDF5 file; model quality (Styner 2003).
#include <fstream>
#include <sstream>

#include "apps/command.h"
#include "shape/core/error.h"
#include "shape/core/log.h"
#include "shape/core/number_format.h"
#include "shape/io/csv_writer.h"
#include "shape/io/mesh_io.h"
#include "shape/model/model_quality.h"
#include "shape/model/shape_grid.h"
#include "shape/model/shape_model.h"
#include "shape/model/statismo_io.h"
#ifdef PECTUS_HAVE_RENDER
#include "shape/model/model_figures.h"
#endif

namespace pectus::cli {
namespace {

namespace fs = std::filesystem;

// Grid meshes (from `pectus resample`) as rows of a shapes matrix; all must have the same vertex count.
struct Training {
  Eigen::MatrixXd shapes;  // N by 3m
  Faces3 faces;            // of the first mesh
  std::vector<std::string> names;
};

std::vector<std::string> ExpandList(const std::vector<std::string>& files, const std::string& list) {
  std::vector<std::string> all = files;
  if (!list.empty()) {
    std::ifstream in(list);
    if (!in) ThrowBadInput(list, "cannot be read");
    std::string line;
    const fs::path base = fs::path(list).parent_path();
    while (std::getline(in, line)) {
      line.erase(0, line.find_first_not_of(" \t\r"));
      line.erase(line.find_last_not_of(" \t\r") + 1);
      if (line.empty() || line[0] == '#') continue;
      all.push_back(fs::path(line).is_absolute() ? line : (base / line).string());
    }
  }
  if (all.empty()) ThrowUsage("no grid files given (positional files or --list)");
  return all;
}

Training ReadGrids(const std::vector<std::string>& files, Report* report) {
  auto t = report->Stage("read");
  Training training;
  std::vector<TriangleMesh> meshes(files.size());
  std::exception_ptr failure;
#pragma omp parallel for schedule(dynamic)
  for (std::size_t k = 0; k < files.size(); ++k) {
    try {
      ReadOptions options;
      options.warn_units = false;
      meshes[k] = ReadMesh(files[k], options);
    } catch (...) {
#pragma omp critical(pectus_model_read)
      failure = std::current_exception();
    }
  }
  if (failure) std::rethrow_exception(failure);
  const Eigen::Index m = meshes[0].num_vertices();
  training.shapes.resize(static_cast<Eigen::Index>(files.size()), 3 * m);
  training.faces = meshes[0].faces;
  for (std::size_t k = 0; k < files.size(); ++k) {
    if (meshes[k].num_vertices() != m) {
      ThrowBadInput(files[k], "has " + std::to_string(meshes[k].num_vertices()) + " vertices; " + files[0] +
                                  " has " + std::to_string(m) +
                                  " (all grids must come from the same `pectus resample --grid`)");
    }
    training.shapes.row(static_cast<Eigen::Index>(k)) =
        ToShapeVector(meshes[k].vertices.positions).transpose();
    training.names.push_back(fs::path(files[k]).stem().string());
  }
  return training;
}

nlohmann::json VarianceJson(const ShapeModel& model, int rows) {
  nlohmann::json modes = nlohmann::json::array();
  const Eigen::VectorXd f = model.ExplainedFraction(), c = model.CumulativeFraction();
  for (int k = 0; k < std::min(rows, model.num_modes()); ++k) {
    modes.push_back(
        {{"mode", k + 1}, {"eigenvalue_mm2", model.variances[k]}, {"explained", f[k]}, {"cumulative", c[k]}});
  }
  return modes;
}

class ModelCommand : public Command {
 public:
  std::string Name() const override { return "model"; }
  std::string Summary() const override {
    return "Shape model of resampled chests: build, info, modes, evaluate (quality), project";
  }
  std::string Example() const override {
    return "  pectus model build grids/*.ply -o chest_model.h5 --scores scores.csv --eigen eigen.csv \\\n"
           "      --variance-png variance.png --mean mean.ply\n"
           "  pectus model info chest_model.h5\n"
           "  pectus model modes chest_model.h5 --mode 1 --mode 2 --sd 3 --out-dir modes/\n"
           "  pectus model evaluate grids/*.ply --csv quality.csv --png quality.png\n"
           "  pectus model project chest_model.h5 new_grid.ply --reconstruction rec.ply";
  }
  void Configure(CLI::App* app) override {
    app->require_subcommand(1);
    build_ = app->add_subcommand("build", "Mean shape and PCA of resampled grids, written as a statismo .h5");
    build_->add_option("grids", files_, "Grid meshes from `pectus resample` (same grid size)");
    build_->add_option("--list", list_, "Text file with one grid path per line (relative to the file)");
    build_->add_option("-o,--output", model_path_, "Model file (.h5, statismo 0.9)")->required();
    build_->add_option("--modes", build_options_.max_modes, "Keep at most this many modes (0: all)")
        ->default_val(0);
    build_->add_option("--noise", build_options_.noise_variance, "Noise variance written to the model, mm^2")
        ->default_val(0.0);
    build_->add_option("--scores", scores_csv_, "CSV of the subjects' scores (mm) per mode");
    build_->add_option("--eigen", eigen_csv_, "CSV of eigenvalues and explained variance per mode");
    build_->add_option("--variance-png", variance_png_, "Plot of variance explained per mode and cumulative");
    build_->add_option("--mean", mean_mesh_, "The mean shape as a mesh");

    info_ = app->add_subcommand("info", "Print what a model holds (points, modes, variance explained)");
    info_->add_option("model", model_in_, "Model file (.h5)")->required();

    modes_ = app->add_subcommand("modes", "Meshes of the mean moved along modes by +-k standard deviations");
    modes_->add_option("model", model_in_, "Model file (.h5)")->required();
    modes_->add_option("--mode", mode_list_, "1-based mode, repeatable (default: 1 and 2)");
    modes_->add_option("--sd", sd_, "Standard deviations, k")->default_val(3.0);
    modes_->add_option("--out-dir", out_dir_, "Folder for mean.ply and mode<j>_<minus|plus><k>sd.ply")
        ->required();
    modes_->add_flag("--png", mode_png_, "Also a colour map per mode of the normal displacement at +k sd");

    evaluate_ =
        app->add_subcommand("evaluate", "Compactness, generalization, specificity vs number of modes");
    evaluate_->add_option("grids", files_, "Grid meshes from `pectus resample`");
    evaluate_->add_option("--list", list_, "Text file with one grid path per line");
    evaluate_->add_option("--max-modes", quality_.max_modes, "Curves up to this many modes (0: N - 2)")
        ->default_val(0);
    evaluate_->add_option("--samples", quality_.specificity_samples, "Random model shapes for specificity")
        ->default_val(200);
    evaluate_->add_option("--seed", quality_.seed, "Random seed")->default_val(quality_.seed);
    evaluate_->add_option("--csv", quality_csv_, "CSV of the three curves");
    evaluate_->add_option("--png", quality_png_, "Plot of the three curves");

    project_ = app->add_subcommand("project", "Scores and reconstruction error of a new grid in the model");
    project_->add_option("model", model_in_, "Model file (.h5)")->required();
    project_->add_option("grid", grid_in_, "Grid mesh from `pectus resample` (same grid as the model)")
        ->required();
    project_->add_option("--modes", project_modes_, "Use the first k modes (-1: all)")->default_val(-1);
    project_->add_option("--reconstruction", reconstruction_, "The reconstruction as a mesh");
    for (CLI::App* sub : {build_, info_, modes_, evaluate_, project_}) sub->fallthrough();
  }
  std::vector<fs::path> Inputs() const override {
    std::vector<fs::path> in(files_.begin(), files_.end());
    if (!list_.empty()) in.push_back(list_);
    if (!model_in_.empty()) in.push_back(model_in_);
    if (!grid_in_.empty()) in.push_back(grid_in_);
    return in;
  }

  void Run(Context* context) override {
    if (build_->parsed()) return Build(context);
    if (info_->parsed()) return Info(context);
    if (modes_->parsed()) return Modes(context);
    if (evaluate_->parsed()) return Evaluate(context);
    if (project_->parsed()) return Project(context);
    ThrowUsage("pectus model needs one of: build, info, modes, evaluate, project");
  }

 private:
  void Build(Context* context) {
    context->report["action"] = "build";
    const auto staged = StageOutput(context, *this, model_path_);
#ifndef PECTUS_HAVE_RENDER
    if (!variance_png_.empty()) ThrowUsage("--variance-png needs pectus built with pectus::render");
#endif
    const Training training = ReadGrids(ExpandList(files_, list_), &context->report);
    ShapeModel model;
    {
      auto t = context->report.Stage("pca");
      model = BuildShapeModel(training.shapes, build_options_, "grids");
    }
    model.faces = training.faces;
    model.names = training.names;
    auto t = context->report.Stage("write");
    WriteStatismoModel(staged, model, {{"source", "pectus model build"}, {"subjects", training.names}});
    if (!scores_csv_.empty()) {
      std::vector<std::string> header{"subject"};
      for (int k = 1; k <= model.num_modes(); ++k) header.push_back("mode" + std::to_string(k) + "_mm");
      WriteCsv(StageOutput(context, *this, scores_csv_), header, model.scores, model.names);
    }
    if (!eigen_csv_.empty()) {
      Eigen::MatrixXd table(model.num_modes(), 4);
      table.col(0) = Eigen::VectorXd::LinSpaced(model.num_modes(), 1, model.num_modes());
      table.col(1) = model.variances;
      table.col(2) = model.ExplainedFraction();
      table.col(3) = model.CumulativeFraction();
      WriteCsv(StageOutput(context, *this, eigen_csv_), {"mode", "eigenvalue_mm2", "explained", "cumulative"},
               table);
    }
    if (!mean_mesh_.empty()) WriteMesh(StageOutput(context, *this, mean_mesh_), model.ToMesh(model.mean));
#ifdef PECTUS_HAVE_RENDER
    if (!variance_png_.empty()) WriteVarianceExplainedPng(StageOutput(context, *this, variance_png_), model);
#endif
    context->report["subjects"] = training.names.size();
    context->report["points"] = model.num_points();
    context->report["modes"] = model.num_modes();
    context->report["total_variance_mm2"] = model.total_variance;
    context->report["variance"] = VarianceJson(model, 20);
    context->report["output"] = model_path_;
    pectus::Info("model: " + model.BriefReport());
  }

  void Info(Context* context) {
    context->report["action"] = "info";
    const ShapeModel model = ReadStatismoModel(model_in_);
    std::ostringstream out;
    out << model_in_ << ": " << model.num_points() << " points, " << model.faces.rows() << " triangles, "
        << model.num_modes() << " modes from " << model.scores.rows() << " subjects; total variance "
        << FormatSignificant(model.total_variance)
        << " mm^2\n  mode  eigenvalue_mm2  explained  cumulative\n";
    const Eigen::VectorXd f = model.ExplainedFraction(), c = model.CumulativeFraction();
    for (int k = 0; k < std::min(10, model.num_modes()); ++k) {
      char line[128];
      std::snprintf(line, sizeof(line), "  %4d  %14.4f  %9.4f  %10.4f\n", k + 1, model.variances[k], f[k],
                    c[k]);
      out << line;
    }
    std::fputs(out.str().c_str(), stdout);
    context->report["points"] = model.num_points();
    context->report["triangles"] = model.faces.rows();
    context->report["modes"] = model.num_modes();
    context->report["subjects"] = model.names;
    context->report["total_variance_mm2"] = model.total_variance;
    context->report["noise_variance_mm2"] = model.noise_variance;
    context->report["variance"] = VarianceJson(model, model.num_modes());
  }

  void Modes(Context* context) {
    context->report["action"] = "modes";
    const ShapeModel model = ReadStatismoModel(model_in_);
#ifndef PECTUS_HAVE_RENDER
    if (mode_png_) ThrowUsage("--png needs pectus built with pectus::render");
#endif
    std::vector<int> modes = mode_list_.empty() ? std::vector<int>{1, 2} : mode_list_;
    for (int j : modes) {
      if (j < 1 || j > model.num_modes()) {
        ThrowUsage("mode " + std::to_string(j) + " does not exist; the model has " +
                   std::to_string(model.num_modes()));
      }
    }
    if (!(sd_ > 0.0)) ThrowUsage("--sd must be > 0");
    const fs::path dir(out_dir_);
    WriteMesh(StageOutput(context, *this, dir / "mean.ply"), model.ToMesh(model.mean));
    nlohmann::json written = nlohmann::json::array();
    char k_text[32];
    std::snprintf(k_text, sizeof(k_text), "%g", sd_);
    for (int j : modes) {
      for (double sign : {-1.0, 1.0}) {
        Eigen::VectorXd b = Eigen::VectorXd::Zero(j);
        b[j - 1] = sign * sd_;
        const Eigen::VectorXd shape = model.Instance(b);
        const std::string name =
            "mode" + std::to_string(j) + "_" + (sign < 0 ? "minus" : "plus") + std::string(k_text) + "sd.ply";
        WriteMesh(StageOutput(context, *this, dir / name), model.ToMesh(shape));
        const Eigen::VectorXd d = VertexDistances(shape, model.mean);
        written.push_back({{"mode", j},
                           {"sd", sign * sd_},
                           {"file", (dir / name).string()},
                           {"max_displacement_mm", d.maxCoeff()}});
#ifdef PECTUS_HAVE_RENDER
        if (mode_png_ && sign > 0) {
          const std::string png = "mode" + std::to_string(j) + "_plus" + std::string(k_text) + "sd.png";
          WriteModeDisplacementPng(StageOutput(context, *this, dir / png), model, j, sd_);
        }
#endif
      }
    }
    context->report["meshes"] = written;
  }

  void Evaluate(Context* context) {
    context->report["action"] = "evaluate";
#ifndef PECTUS_HAVE_RENDER
    if (!quality_png_.empty()) ThrowUsage("--png needs pectus built with pectus::render");
#endif
    std::string why;
    if (!quality_.IsValid(&why)) ThrowUsage(why);
    const fs::path csv = quality_csv_.empty() ? fs::path() : StageOutput(context, *this, quality_csv_);
    const fs::path png = quality_png_.empty() ? fs::path() : StageOutput(context, *this, quality_png_);
    const Training training = ReadGrids(ExpandList(files_, list_), &context->report);
    ModelQualityCurves q;
    {
      auto t = context->report.Stage("quality");
      q = EvaluateModelQuality(training.shapes, quality_);
    }
    Eigen::MatrixXd table(q.modes.size(), 7);
    table << q.modes.cast<double>(), q.compactness, q.compactness_sd, q.generalization_mm,
        q.generalization_sd, q.specificity_mm, q.specificity_sd;
    if (!csv.empty()) {
      WriteCsv(csv,
               {"modes", "compactness_mm2", "compactness_sd_mm2", "generalization_mm", "generalization_sd_mm",
                "specificity_mm", "specificity_sd_mm"},
               table);
    }
#ifdef PECTUS_HAVE_RENDER
    if (!png.empty()) WriteQualityCurvesPng(png, q);
#endif
    nlohmann::json rows = nlohmann::json::array();
    for (Eigen::Index r = 0; r < table.rows(); ++r) {
      rows.push_back({{"modes", q.modes[r]},
                      {"compactness_mm2", q.compactness[r]},
                      {"generalization_mm", q.generalization_mm[r]},
                      {"generalization_sd_mm", q.generalization_sd[r]},
                      {"specificity_mm", q.specificity_mm[r]},
                      {"specificity_sd_mm", q.specificity_sd[r]}});
    }
    context->report["subjects"] = training.names.size();
    context->report["quality"] = rows;
  }

  void Project(Context* context) {
    context->report["action"] = "project";
    const fs::path rec = reconstruction_.empty() ? fs::path() : StageOutput(context, *this, reconstruction_);
    const ShapeModel model = ReadStatismoModel(model_in_);
    ReadOptions options;
    options.warn_units = false;
    const TriangleMesh grid = ReadMesh(grid_in_, options);
    if (grid.num_vertices() != model.num_points()) {
      ThrowBadInput(grid_in_, "has " + std::to_string(grid.num_vertices()) +
                                  " vertices; the model's grid has " + std::to_string(model.num_points()));
    }
    const ShapeProjection p = ProjectShape(model, ToShapeVector(grid.vertices.positions), project_modes_);
    if (!rec.empty()) WriteMesh(rec, model.ToMesh(p.reconstruction));
    nlohmann::json scores = nlohmann::json::array();
    for (Eigen::Index k = 0; k < p.scores.size(); ++k) {
      scores.push_back({{"mode", k + 1}, {"score_mm", p.scores[k]}, {"score_sd", p.scores_sd[k]}});
    }
    context->report["scores"] = scores;
    context->report["reconstruction_rms_mm"] = p.rms_error_mm;
    context->report["reconstruction_max_mm"] = p.max_error_mm;
    context->report["mahalanobis"] = p.mahalanobis;
    std::printf("%s: %lld modes, reconstruction RMS %s (max %s), Mahalanobis distance %s\n", grid_in_.c_str(),
                static_cast<long long>(p.scores.size()), FormatMm(p.rms_error_mm).c_str(),
                FormatMm(p.max_error_mm).c_str(), FormatSignificant(p.mahalanobis).c_str());
  }

  CLI::App *build_ = nullptr, *info_ = nullptr, *modes_ = nullptr, *evaluate_ = nullptr, *project_ = nullptr;
  std::vector<std::string> files_;
  std::string list_, model_path_, scores_csv_, eigen_csv_, variance_png_, mean_mesh_;
  std::string model_in_, out_dir_, quality_csv_, quality_png_, grid_in_, reconstruction_;
  std::vector<int> mode_list_;
  double sd_ = 3.0;
  bool mode_png_ = false;
  int project_modes_ = -1;
  ShapeModelOptions build_options_;
  ModelQualityOptions quality_;
};

PECTUS_REGISTER_COMMAND(ModelCommand, 90);

}  // namespace
}  // namespace pectus::cli
