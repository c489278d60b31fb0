// pectus serve: the surgeon's planner in the browser (issue 15). A local HTTP server that serves the
// planner page (embedded in the binary at build time: planner_page_files.h) and a small JSON API over the
// same C++ as `pectus plan`: the patients of a CT table, a patient's ribcage, skin, landmarks and response
// basis (binary float32; docs/planner.md, "Planner in the browser"), the average chest of a model, and a
// plan scored (scenarios A and B, the best-placement search) by MakeNussPlan itself.
//
// Safe by default (STYLE 13): it binds 127.0.0.1; every request carries the random token of the printed
// URL (query `token`, header X-Pectus-Token, or the cookie the page gets), compared in constant time; the
// Host header must name this server (127.0.0.1:PORT or localhost:PORT: no DNS rebinding); only the files
// named in the options are read; bodies over a limit get 413; bad JSON 400 with a message; every /api
// answer is JSON or binary, every error {"error": message}. No request can stop or stall the server: a
// handler's exception becomes a 500 with its message, and slow work holds one worker thread only.
#pragma once

#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace pectus::serve {

/// What the server serves and how.
struct PlannerServerOptions {
  std::filesystem::path patient_table;    ///< CSV of CT measurements (required)
  std::filesystem::path model;            ///< the average chest: a statismo model .h5 (required)
  std::filesystem::path model_landmarks;  ///< its landmarks, if the model has none (optional)
  std::filesystem::path basis;     ///< bases.h5 of `pectus surrogate build`: load, not build (optional)
  std::filesystem::path plugin;    ///< the planner plugin (empty: beside pectus)
  std::string host = "127.0.0.1";  ///< address bound; loopback only unless asked otherwise
  int port = 8765;                 ///< 0: a free port, told by port() and url()
  /// UDP port of the trainer's device protocol for outside drivers (device_protocol.h): -1 none (the
  /// default), 0 a free one, told by device_port()
  int device_port = -1;
  std::string token;                     ///< empty: 32 random hex characters (std::random_device)
  std::size_t max_body_bytes = 1 << 20;  ///< larger request bodies get 413. Default 1 MiB
  /// Worker threads answering requests. A keep-alive connection holds one while it is open (a browser
  /// keeps up to 6 per page), so there are more than clients expected at once. Default 32
  int threads = 32;
  int max_patients = 4;  ///< patients kept in memory (planner + basis), least recent out
  /// The planner's mesh and materials, as `pectus plan`'s options (0 or < 0: the plugin's defaults).
  double cell_mm = 0, cartilage_mpa = 0, soft_tissue_mm = -1;
  /// Bar levels of the page's coefficient table, mm apart along the sternum (docs/planner.md). 0.25.
  double table_step_mm = 0.25;

  /// False, with the reason, for a missing file option or a value out of range.
  bool IsValid(std::string* why) const;
};

/// The server: loads the plugin, the patient list and the average chest on construction (throws
/// pectus::Error naming the file at fault), answers requests between Start() and Stop().
class PlannerServer {
 public:
  explicit PlannerServer(PlannerServerOptions options);
  ~PlannerServer();
  PlannerServer(const PlannerServer&) = delete;
  PlannerServer& operator=(const PlannerServer&) = delete;

  /// Binds the address and port (throws Error(kFailure) if it cannot) and answers on a thread of its
  /// own until Stop().
  void Start();
  /// Blocks until the server stops (Stop() from another thread, or a signal handler calling it).
  void Wait();
  /// The table's patient ids, in its order.
  const std::vector<std::string>& patient_ids() const;
  /// Starts making patient `id` (planner, basis, the page's arrays) in the background, so that the page
  /// opens on it without waiting; after Start(). Throws Error(kUsage) for an id not in the table.
  void Prepare(const std::string& id);
  /// Blocks until what Prepare() started is made (at once if nothing); false, with the reason, if it could
  /// not be made.
  bool WaitUntilPrepared(std::string* why = nullptr);
  /// Stops answering; idempotent.
  void Stop();

  int port() const;
  /// The device protocol's UDP port (-1 if not asked for).
  int device_port() const;
  const std::string& token() const;
  /// The page's address with the token: http://127.0.0.1:PORT/?token=...
  std::string url() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// Whether two strings are equal, in time that depends on their lengths only.
bool ConstantTimeEquals(const std::string& a, const std::string& b);

}  // namespace pectus::serve
