// describe_scenario: what a scenario of the simulated rig holds (tabletop_sim/scenario.h).
//
//   describe_scenario NAME...        the description of each (person, light, cameras, room)
//   describe_scenario --cameras NAME the number of cameras it brings (what the synchroniser
//                                    must be told; demo.sh uses it)
//   describe_scenario --list         the names: default, the presets, random-<seed>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "tabletop_sim/scenario.h"

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "--help")) {
    std::fprintf(stderr, "usage: describe_scenario NAME... | --cameras NAME | --list\n");
    return argc < 2 ? 2 : 0;
  }
  try {
    if (!std::strcmp(argv[1], "--list")) {
      std::printf("default\nrandom-<seed>\n");
      for (const std::string& p : tabletop_sim::scenarioPresets()) std::printf("%s\n", p.c_str());
      return 0;
    }
    if (!std::strcmp(argv[1], "--cameras")) {
      if (argc != 3) throw std::invalid_argument("--cameras takes one scenario name");
      const tabletop_sim::Scenario s = tabletop_sim::scenarioByName(argv[2]);
      std::printf("%d\n", s.rig.cameras.empty() ? 8 : static_cast<int>(s.rig.cameras.size()));
      return 0;
    }
    for (int i = 1; i < argc; ++i)
      std::printf("%s", tabletop_sim::scenarioByName(argv[i]).describe().c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "describe_scenario: %s\n", e.what());
    return 1;
  }
  return 0;
}
