#include <iostream>

#include "tools/cli/cli.hpp"
#ifdef LIMBER_VIEWER
#include "tools/viewer/view_app.hpp"
#endif

int main(int argc, char** argv) {
#ifdef LIMBER_VIEWER
  const limber::cli::Viewer viewer = limber::viewer::run_viewer;
#else
  const limber::cli::Viewer viewer = nullptr;
#endif
  return limber::cli::run_main(argc, argv, std::cout, std::cerr, viewer);
}
