# SPDX-License-Identifier: MIT
"""The paper's own examples (§4): data, exact solutions and problem builders, kept apart from the
general code.

* :mod:`.bar1d`: the 1-D normal-compliance test (§4.2.1) with its exact solution and the error
  measures of Figs. 5–7;
* :mod:`.signorini`: the 2-D (§4.1.1) and 3-D (§4.1.2) Signorini tests, with the misprints of the
  printed data corrected (see its docstring).

The same problems are also bundled as scene files (``vpcontact list``).
"""

from vpcontact.paper import bar1d, signorini

__all__ = ["bar1d", "signorini"]
