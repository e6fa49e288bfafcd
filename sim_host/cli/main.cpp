// hyq_sim: see sim_host/README.md and docs/scenarios.md.
#include "sim_host/loop/run.hpp"

int main(int argc, char** argv) { return hyq::sim::cliMain(argc, argv); }
