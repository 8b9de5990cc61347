// SPDX-License-Identifier: MIT
#include <pybind11/pybind11.h>
PYBIND11_MODULE(_cpp, m) { m.doc() = "placeholder"; }
