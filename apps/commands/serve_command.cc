// pectus serve: the surgeon's planner in the browser (issue 15): a local web server (apps/serve) serving
// the planner page and its JSON API until Ctrl-C. Prints the page's URL, with its token.
#include <csignal>
#include <cstdio>
#include <thread>

#include "apps/command.h"
#include "apps/serve/planner_server.h"
#include "shape/core/error.h"

namespace pectus::cli {
namespace {

class ServeCommand : public Command {
 public:
  std::string Name() const override { return "serve"; }
  std::string Summary() const override {
    return "The Nuss planner in the browser: a local web server for the planner page (prints its URL)";
  }
  std::string Example() const override {
    return "  pectus serve --patient-table ../shared/datasets/patients/nuss_ct_parameters.csv \\\n"
           "      --model out/demo/model/model.h5\n"
           "    (open the printed http://127.0.0.1:8765/?token=... in a browser; Ctrl-C stops it)\n"
           "  pectus serve --patient-table nuss_ct_parameters.csv --model model.h5 --basis bases.h5 --port "
           "0\n"
           "    (patients' bases from `pectus surrogate build`; a free port, told in the URL)";
  }
  void Configure(CLI::App* app) override {
    app->add_option("--patient-table", options_.patient_table, "CSV of CT measurements (as `pectus plan`)")
        ->required();
    app->add_option("--model", options_.model,
                    "The average chest: a statismo model from `pectus model build`")
        ->required();
    app->add_option("--model-landmarks", options_.model_landmarks,
                    "Landmarks of the average chest, if the model file has none");
    app->add_option("--basis", options_.basis,
                    "Take the patients' response bases from this file (`pectus surrogate build`) instead of "
                    "building them (2-3 s per patient, once)");
    app->add_option("--patient", patient_,
                    "The patient the page opens on, made as the server starts (default: the table's first)");
    app->add_option("--port", options_.port, "Port on 127.0.0.1; 0 picks a free one")->default_val(8765);
    app->add_option("--device-port", options_.device_port,
                    "UDP port for an outside haptic device's driver (the trainer's device protocol, "
                    "docs/trainer.md); 0 picks a free one; none unless given");
    app->add_option("--max-body-bytes", options_.max_body_bytes, "Larger request bodies get 413")
        ->default_val(1 << 20);
    app->add_option("--cartilage-modulus", options_.cartilage_mpa, "As `pectus plan` (MPa)");
    app->add_option("--cell-mm", options_.cell_mm, "As `pectus plan`: mesh cell length along the ribs, mm");
    app->add_option("--soft-tissue-mm", options_.soft_tissue_mm,
                    "As `pectus plan`: soft tissue over the bones, mm");
    app->add_option("--plugin", plugin_,
                    "The planner plugin (default: beside pectus, or PECTUS_PLANNER_PLUGIN)");
  }
  std::vector<std::filesystem::path> Inputs() const override {
    std::vector<std::filesystem::path> in{options_.patient_table, options_.model};
    if (!options_.basis.empty()) in.push_back(options_.basis);
    if (!options_.model_landmarks.empty()) in.push_back(options_.model_landmarks);
    return in;
  }

  void Run(Context* context) override {
    options_.plugin = plugin_;
    std::string why;
    if (!options_.IsValid(&why)) ThrowUsage(why);
    // Ctrl-C and SIGTERM are taken by a thread of their own (sigwait), which stops the server: no work in
    // a signal handler. Blocked before any thread starts, so every thread inherits the mask.
    sigset_t signals;
    sigemptyset(&signals);
    sigaddset(&signals, SIGINT);
    sigaddset(&signals, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &signals, nullptr);
    serve::PlannerServer server(options_);
    const std::string patient = patient_.empty() ? server.patient_ids().front() : patient_;
    server.Start();
    // The page opens on `patient`: made now, while the user opens the page.
    server.Prepare(patient);
    std::printf("pectus serve: the planner is at %s%s\n", server.url().c_str(),
                patient_.empty() ? "" : ("&patient=" + patient).c_str());
    if (server.device_port() >= 0)
      std::printf("pectus serve: device drivers send to UDP %s:%d (docs/trainer.md)\n", "127.0.0.1",
                  server.device_port());
    std::printf("pectus serve: making patient %s (its ribcage and response basis: seconds)...\n",
                patient.c_str());
    std::fflush(stdout);
    std::thread announcer([&] {
      std::string failure;
      if (server.WaitUntilPrepared(&failure)) {
        std::printf("pectus serve: patient %s is ready\n", patient.c_str());
      } else {
        std::fprintf(stderr, "pectus serve: patient %s could not be made: %s\n", patient.c_str(),
                     failure.c_str());
      }
      std::fflush(stdout);
    });
    std::thread waiter([&] {
      int signal = 0;
      sigwait(&signals, &signal);
      server.Stop();
    });
    server.Wait();
    // Stopped by a signal: the waiter has returned.
    waiter.join();
    announcer.join();
    context->report["port"] = server.port();
  }

 private:
  serve::PlannerServerOptions options_;
  std::string plugin_;
  std::string patient_;
};

}  // namespace

PECTUS_REGISTER_COMMAND(ServeCommand, 130);

}  // namespace pectus::cli
