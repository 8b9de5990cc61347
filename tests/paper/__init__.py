# SPDX-License-Identifier: MIT
"""The paper's tests (§4) against their exact solutions and observed orders."""
