#include <iostream>

#include "tools/cli/cli.hpp"

int main(int argc, char** argv) { return limber::cli::run_main(argc, argv, std::cout, std::cerr); }
