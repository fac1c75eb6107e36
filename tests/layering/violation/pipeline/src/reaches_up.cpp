// A planted violation for the layering check's own test: pipeline may not include sim_camera.
#include "flowsteer/sim_camera/world.hpp"
