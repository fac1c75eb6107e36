// A planted violation for the layering check's own test: drivers may not include servo.
#include "flowsteer/servo/control.hpp"
