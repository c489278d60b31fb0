// merge_grid_benchmark: its command-line flags (the grid of tracker error, overlap, sampling and sweep
// count; the merge's overrides; the peers and outputs), parsed once.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

namespace pectus::merge_grid {

struct Flags {
  std::vector<double> skin = {0, 4}, overlap = {0.1, 0.2, 0.4};
  std::vector<std::string> sampling = {"grid", "random"};
  std::vector<double> sweeps = {5};
  int seeds = 1, seed = 1;
  std::string pattern = "horizontal", png = "merge_grid.png", workdir = "/tmp/pectus_merge_grid";
  double spacing_mm = 1.5, success_mm = 1.0, lever_mm = 200.0;
  double prior_deg = -1.0, prior_mm = -1.0, prior_lever_mm = -1.0;  // < 0: MergeSweeps's defaults
  double min_overlap_fraction = -1.0, border_gap_deg = -1.0;        // < 0: MergeSweeps's defaults
  double min_pinned_ratio = -1.0;                                   // < 0: MergeSweeps's default
  double final_pinned_ratio = -1.0;                                 // < 0: MergeSweeps's default
  double sample_spacings = -1.0;                                    // < 0: MergeSweeps's default
  int normal_neighbours = -1;                                       // < 0: MergeSweeps's default
  bool model_bound = false;      // also the shape figure the merge's own information at the truth predicts
  double noise_mm = -1.0;        // < 0: the scanner's default range noise
  bool start_at_truth = false;   // also the merge started at the truth but held to the tracker's readings
  int points_per_pair = -1;      // < 0: MergeSweeps's default
  int rounds = -1;               // < 0: MergeSweeps's default
  int fit_tracker = -1;          // 0 / 1; < 0: MergeSweeps's default
  int final_every_point = -1;    // 0 / 1; < 0: MergeSweeps's default
  int count_shared_points = -1;  // 0 / 1; < 0: MergeSweeps's default
  double max_view_angle_deg = -1.0;   // < 0: MergeSweeps's default
  double sight_radius_widths = -1.0;  // < 0: MergeSweeps's default
  int plane_points = 0;               // 0: MergeSweeps's default
  bool open3d = true;
};

inline std::vector<double> Numbers(const std::string& text) {
  std::vector<double> v;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) v.push_back(std::stod(item));
  return v;
}

inline std::vector<std::string> Words(const std::string& text) {
  std::vector<std::string> v;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) v.push_back(item);
  return v;
}

inline Flags Parse(int argc, char** argv) {
  Flags f;
  for (int a = 1; a < argc; ++a) {
    const std::string key = argv[a];
    auto value = [&]() -> std::string {
      if (a + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", key.c_str());
        std::exit(2);
      }
      return argv[++a];
    };
    if (key == "--full") {
      f.skin = {0, 2, 4, 6};
      f.overlap = {0.10, 0.15, 0.20, 0.30, 0.40};
      f.sampling = {"grid", "random"};
      f.sweeps = {3, 5, 8};
    } else if (key == "--skin")
      f.skin = Numbers(value());
    else if (key == "--overlap")
      f.overlap = Numbers(value());
    else if (key == "--sampling")
      f.sampling = Words(value());
    else if (key == "--sweeps")
      f.sweeps = Numbers(value());
    else if (key == "--seeds")
      f.seeds = std::stoi(value());
    else if (key == "--seed")
      f.seed = std::stoi(value());
    else if (key == "--pattern")
      f.pattern = value();
    else if (key == "--spacing")
      f.spacing_mm = std::stod(value());
    else if (key == "--success-mm")
      f.success_mm = std::stod(value());
    else if (key == "--lever")
      f.lever_mm = std::stod(value());
    else if (key == "--prior-deg")
      f.prior_deg = std::stod(value());
    else if (key == "--prior-mm")
      f.prior_mm = std::stod(value());
    else if (key == "--prior-lever")
      f.prior_lever_mm = std::stod(value());
    else if (key == "--min-overlap-fraction")
      f.min_overlap_fraction = std::stod(value());
    else if (key == "--border-gap")
      f.border_gap_deg = std::stod(value());
    else if (key == "--min-pinned-ratio")
      f.min_pinned_ratio = std::stod(value());
    else if (key == "--final-pinned-ratio")
      f.final_pinned_ratio = std::stod(value());
    else if (key == "--sample-spacings")
      f.sample_spacings = std::stod(value());
    else if (key == "--noise-mm")
      f.noise_mm = std::stod(value());
    else if (key == "--start-at-truth")
      f.start_at_truth = true;
    else if (key == "--model-bound")
      f.model_bound = true;
    else if (key == "--normal-neighbours")
      f.normal_neighbours = std::stoi(value());
    else if (key == "--fit-tracker")
      f.fit_tracker = std::stoi(value());
    else if (key == "--final-every-point")
      f.final_every_point = std::stoi(value());
    else if (key == "--sight-radius")
      f.sight_radius_widths = std::stod(value());
    else if (key == "--plane-points")
      f.plane_points = std::stoi(value());
    else if (key == "--max-view-angle")
      f.max_view_angle_deg = std::stod(value());
    else if (key == "--count-shared-points")
      f.count_shared_points = std::stoi(value());
    else if (key == "--rounds")
      f.rounds = std::stoi(value());
    else if (key == "--points-per-pair")
      f.points_per_pair = std::stoi(value());
    else if (key == "--png")
      f.png = value();
    else if (key == "--workdir")
      f.workdir = value();
    else if (key == "--no-open3d")
      f.open3d = false;
    else {
      std::fprintf(stderr, "unknown flag %s (see the comment at the top of merge_grid_benchmark.cc)\n",
                   key.c_str());
      std::exit(2);
    }
  }
  return f;
}

}  // namespace pectus::merge_grid
