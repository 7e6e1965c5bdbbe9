// write_default_rig: writes the simulated rig's built-in camera layout as a rig YAML (the
// committed config/sim_rig.yaml is its output, with the format documentation on top).
//   write_default_rig OUT.yaml [num_cameras] [width] [height]
#include <cstdio>
#include <cstdlib>

#include "tabletop_capture/default_rig.h"

int main(int argc, char** argv) {
  if (argc < 2 || argc > 5) {
    std::fprintf(stderr, "usage: write_default_rig OUT.yaml [num_cameras=8] [width=320] [height=240]\n");
    return 2;
  }
  tabletop_capture::DefaultRigOptions o;
  if (argc > 2) o.num_cameras = std::atoi(argv[2]);
  if (argc > 3) o.width = std::atoi(argv[3]);
  if (argc > 4) o.height = std::atoi(argv[4]);
  try {
    tabletop_capture::saveRigYaml(tabletop_capture::makeDefaultRig(o), argv[1]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "write_default_rig: %s\n", e.what());
    return 1;
  }
  std::printf("wrote %s (%d cameras %dx%d)\n", argv[1], o.num_cameras, o.width, o.height);
  return 0;
}
