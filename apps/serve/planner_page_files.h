// pectus serve: the planner page's built files (apps/planner_page, `vite build`), embedded in the binary
// at build time (apps/planner_page/embed.mjs writes planner_page_files.cc), so that the server reads no
// file but those named on its command line.
#pragma once

#include <cstddef>

namespace pectus::serve {

/// One file of the built page.
struct EmbeddedFile {
  const char* path;           ///< URL path, "/index.html", "/assets/index-1a2b3c.js"
  const unsigned char* data;  ///< its bytes
  std::size_t size;
  const char* mime;  ///< Content-Type
};

/// The page's files (kPlannerPageFileCount of them).
extern const EmbeddedFile kPlannerPageFiles[];
extern const std::size_t kPlannerPageFileCount;

}  // namespace pectus::serve
