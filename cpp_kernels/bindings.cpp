// SPDX-License-Identifier: MIT
// Thin pybind11 bindings of the C++ kernels into the private module vpcontact._cpp.
// Inputs cross as C-contiguous float64 arrays (no copy when already so); outputs are
// caller-provided arrays written in place (noconvert, so a temporary copy can never
// swallow the result). The only checks here are the array shapes the raw-pointer
// kernels rely on; everything else is validated in C++ (std::invalid_argument ->
// ValueError) or in vpcontact/kernels.py.
#include <vpcontact/kernels.hpp>
#include <vpcontact/patch_smoother.hpp>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace py = pybind11;
using namespace vpcontact;

namespace
{
using InArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
using OutArray = py::array_t<double, py::array::c_style>;
// The tangent output may be None: the kernels then skip it (and, for the implicit updates,
// the work of computing it).
using OptionalOut = std::optional<OutArray>;
using IndexArray = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;

void check_shape(const py::array& a, const std::vector<py::ssize_t>& shape, const char* name)
{
  bool ok = a.ndim() == static_cast<py::ssize_t>(shape.size());
  for (std::size_t i = 0; ok && i < shape.size(); ++i)
    ok = a.shape(i) == shape[i];
  if (!ok)
  {
    std::string expected;
    for (auto s : shape)
      expected += (expected.empty() ? "" : ", ") + (s < 0 ? std::string("N") : std::to_string(s));
    throw std::invalid_argument(std::string(name) + ": expected shape (" + expected + ")");
  }
}

const double* in(const InArray& a, const std::vector<py::ssize_t>& shape, const char* name)
{
  check_shape(a, shape, name);
  return a.data();
}

double* out(OutArray& a, const std::vector<py::ssize_t>& shape, const char* name)
{
  check_shape(a, shape, name);
  return a.mutable_data(); // throws if not writeable
}

Elasticity elasticity(const std::string& model, double E, double nu)
{
  return {parse_model(model), E, nu};
}

StepArrays step_arrays(Model model, const InArray& sigma_old, const InArray& eps_old,
                       const InArray& eps_new, OutArray& sigma_new, OptionalOut& tangent)
{
  const py::ssize_t n = mandel_size(model);
  const py::ssize_t N = sigma_old.ndim() == 2 ? sigma_old.shape(0) : -1;
  StepArrays step;
  step.num_points = static_cast<std::size_t>(N < 0 ? 0 : N);
  step.sigma_old = in(sigma_old, {N, n}, "sigma_old");
  step.eps_old = in(eps_old, {N, n}, "eps_old");
  step.eps_new = in(eps_new, {N, n}, "eps_new");
  step.sigma_new = out(sigma_new, {N, n}, "sigma_new");
  step.tangent = tangent ? out(*tangent, {N, n, n}, "tangent") : nullptr;
  return step;
}

LocalCsr local_csr(const IndexArray& row_start, const IndexArray& columns, const InArray& values,
                   std::int64_t first_column)
{
  if (row_start.ndim() != 1 || row_start.shape(0) < 1)
    throw std::invalid_argument("row_start: expected shape (rows + 1)");
  const py::ssize_t rows = row_start.shape(0) - 1;
  const py::ssize_t nnz = row_start.at(rows);
  check_shape(columns, {nnz}, "columns");
  check_shape(values, {nnz}, "values");
  return {static_cast<std::size_t>(rows), row_start.data(), columns.data(), values.data(),
          first_column};
}

// py::arg list shared by the stress updates.
#define STEP_ARGS                                                                                  \
  py::arg("sigma_old"), py::arg("eps_old"), py::arg("eps_new"), py::arg("sigma_new").noconvert(),  \
      py::arg("tangent").noconvert()
} // namespace

PYBIND11_MODULE(_cpp, m)
{
  m.doc() = "Private C++ kernels of vpcontact; use vpcontact.kernels instead.";

  m.def("dimension", [](const std::string& model) { return dimension(parse_model(model)); });
  m.def("mandel_size", [](const std::string& model) { return mandel_size(parse_model(model)); });

  m.def(
      "to_mandel",
      [](int d, const InArray& t, OutArray& mandel)
      {
        const py::ssize_t N = t.ndim() == 3 ? t.shape(0) : -1;
        const double* src = in(t, {N, d, d}, "t");
        double* dst = out(mandel, {N, mandel_size_of_dimension(d)}, "out");
        py::gil_scoped_release release;
        to_mandel(d, static_cast<std::size_t>(N), src, dst);
      },
      py::arg("d"), py::arg("t"), py::arg("out").noconvert());
  m.def(
      "from_mandel",
      [](int d, const InArray& mandel, OutArray& t)
      {
        const py::ssize_t N = mandel.ndim() == 2 ? mandel.shape(0) : -1;
        const double* src = in(mandel, {N, mandel_size_of_dimension(d)}, "m");
        double* dst = out(t, {N, d, d}, "out");
        py::gil_scoped_release release;
        from_mandel(d, static_cast<std::size_t>(N), src, dst);
      },
      py::arg("d"), py::arg("m"), py::arg("out").noconvert());
  m.def(
      "matrix_from_mandel",
      [](int d, const InArray& C, OutArray& T)
      {
        const py::ssize_t n = mandel_size_of_dimension(d);
        const py::ssize_t N = C.ndim() == 3 ? C.shape(0) : -1;
        const double* src = in(C, {N, n, n}, "C");
        double* dst = out(T, {N, d, d, d, d}, "out");
        py::gil_scoped_release release;
        matrix_from_mandel(d, static_cast<std::size_t>(N), src, dst);
      },
      py::arg("d"), py::arg("C"), py::arg("out").noconvert());

  m.def(
      "elasticity_matrix",
      [](const std::string& model, double E, double nu)
      {
        const Elasticity el = elasticity(model, E, nu);
        const py::ssize_t n = mandel_size(el.model);
        OutArray C({n, n});
        elasticity_matrix(el, C.mutable_data());
        return C;
      },
      py::arg("model"), py::arg("E"), py::arg("nu"));
  m.def(
      "yield_matrix",
      [](const std::string& model)
      {
        const Model mod = parse_model(model);
        const py::ssize_t n = mandel_size(mod);
        OutArray Y({n, n});
        yield_matrix(mod, Y.mutable_data());
        return Y;
      },
      py::arg("model"));
  m.def(
      "yield_function",
      [](const std::string& model, const InArray& tau, OutArray& values)
      {
        const Model mod = parse_model(model);
        const py::ssize_t N = tau.ndim() == 2 ? tau.shape(0) : -1;
        const double* src = in(tau, {N, mandel_size(mod)}, "sigma");
        double* dst = out(values, {N}, "out");
        py::gil_scoped_release release;
        yield_function(mod, static_cast<std::size_t>(N), src, dst);
      },
      py::arg("model"), py::arg("sigma"), py::arg("out").noconvert());

  m.def(
      "project",
      [](const std::string& model, double E, double nu, double sigma_y, const InArray& sigma,
         OutArray& tau)
      {
        const Elasticity el = elasticity(model, E, nu);
        const py::ssize_t N = sigma.ndim() == 2 ? sigma.shape(0) : -1;
        const double* src = in(sigma, {N, mandel_size(el.model)}, "sigma");
        double* dst = out(tau, {N, mandel_size(el.model)}, "out");
        py::gil_scoped_release release;
        project(el, sigma_y, static_cast<std::size_t>(N), src, dst);
      },
      py::arg("model"), py::arg("E"), py::arg("nu"), py::arg("sigma_y"), py::arg("sigma"),
      py::arg("out").noconvert());

  m.def(
      "perzyna_update",
      [](const std::string& scheme, const std::string& model, double E, double nu, double sigma_y,
         double mu_star, double dt, const InArray& sigma_old, const InArray& eps_old,
         const InArray& eps_new, OutArray& sigma_new, OptionalOut tangent)
      {
        const Scheme sch = parse_scheme(scheme);
        const Elasticity el = elasticity(model, E, nu);
        const StepArrays step
            = step_arrays(el.model, sigma_old, eps_old, eps_new, sigma_new, tangent);
        py::gil_scoped_release release;
        perzyna_update(sch, el, sigma_y, mu_star, dt, step);
      },
      py::arg("scheme"), py::arg("model"), py::arg("E"), py::arg("nu"), py::arg("sigma_y"),
      py::arg("mu_star"), py::arg("dt"), STEP_ARGS);
  m.def(
      "perzyna_update_newton",
      [](const std::string& model, double E, double nu, double sigma_y, double mu_star, double dt,
         const InArray& sigma_old, const InArray& eps_old, const InArray& eps_new,
         OutArray& sigma_new, OptionalOut tangent)
      {
        const Elasticity el = elasticity(model, E, nu);
        const StepArrays step
            = step_arrays(el.model, sigma_old, eps_old, eps_new, sigma_new, tangent);
        py::gil_scoped_release release;
        perzyna_update_newton(el, sigma_y, mu_star, dt, step);
      },
      py::arg("model"), py::arg("E"), py::arg("nu"), py::arg("sigma_y"), py::arg("mu_star"),
      py::arg("dt"), STEP_ARGS);
  m.def(
      "linear_update",
      [](const std::string& scheme, const std::string& model, double E, double nu, double a,
         double b, double dt, const InArray& sigma_old, const InArray& eps_old,
         const InArray& eps_new, OutArray& sigma_new, OptionalOut tangent)
      {
        const Scheme sch = parse_scheme(scheme);
        const Elasticity el = elasticity(model, E, nu);
        const StepArrays step
            = step_arrays(el.model, sigma_old, eps_old, eps_new, sigma_new, tangent);
        py::gil_scoped_release release;
        linear_update(sch, el, a, b, dt, step);
      },
      py::arg("scheme"), py::arg("model"), py::arg("E"), py::arg("nu"), py::arg("a"), py::arg("b"),
      py::arg("dt"), STEP_ARGS);
  m.def(
      "linear_update_newton",
      [](const std::string& model, double E, double nu, double a, double b, double dt,
         const InArray& sigma_old, const InArray& eps_old, const InArray& eps_new,
         OutArray& sigma_new, OptionalOut tangent)
      {
        const Elasticity el = elasticity(model, E, nu);
        const StepArrays step
            = step_arrays(el.model, sigma_old, eps_old, eps_new, sigma_new, tangent);
        py::gil_scoped_release release;
        linear_update_newton(el, a, b, dt, step);
      },
      py::arg("model"), py::arg("E"), py::arg("nu"), py::arg("a"), py::arg("b"), py::arg("dt"),
      STEP_ARGS);

  py::class_<PatchSmoother>(m, "PatchSmoother")
      .def(py::init(
               [](const IndexArray& offsets, const IndexArray& indices, std::size_t num_rows)
               {
                 check_shape(offsets, {offsets.ndim() == 1 ? offsets.shape(0) : -2}, "offsets");
                 check_shape(indices, {indices.ndim() == 1 ? indices.shape(0) : -2}, "indices");
                 return PatchSmoother(
                     std::vector<std::int64_t>(offsets.data(), offsets.data() + offsets.size()),
                     std::vector<std::int64_t>(indices.data(), indices.data() + indices.size()),
                     num_rows);
               }),
           py::arg("offsets"), py::arg("indices"), py::arg("num_rows"))
      .def_property_readonly("size", &PatchSmoother::size)
      .def_property_readonly("singular", &PatchSmoother::singular)
      .def(
          "factorize",
          [](PatchSmoother& self, const IndexArray& row_start, const IndexArray& columns,
             const InArray& values, std::int64_t first_column,
             const std::optional<IndexArray>& patches)
          {
            const LocalCsr A = local_csr(row_start, columns, values, first_column);
            const std::int64_t* listed = patches ? patches->data() : nullptr;
            const std::size_t count = patches ? static_cast<std::size_t>(patches->size()) : 0;
            py::gil_scoped_release release;
            self.factorize(A, listed, count);
          },
          py::arg("row_start"), py::arg("columns"), py::arg("values"),
          py::arg("first_column") = 0, py::arg("patches") = py::none())
      .def(
          "schur_sum",
          [](const PatchSmoother& self, const IndexArray& row_start, const IndexArray& columns,
             const InArray& values, const std::optional<IndexArray>& patches)
          {
            const LocalCsr Bt = local_csr(row_start, columns, values, 0);
            const std::int64_t* listed = patches ? patches->data() : nullptr;
            const std::size_t count = patches ? static_cast<std::size_t>(patches->size()) : 0;
            std::vector<std::int64_t> rows, cols, starts;
            std::vector<double> entries;
            {
              py::gil_scoped_release release;
              self.schur_sum(Bt, rows, cols, entries, starts, listed, count);
            }
            return py::make_tuple(py::array_t<std::int64_t>(rows.size(), rows.data()),
                                  py::array_t<std::int64_t>(cols.size(), cols.data()),
                                  py::array_t<double>(entries.size(), entries.data()),
                                  py::array_t<std::int64_t>(starts.size(), starts.data()));
          },
          py::arg("row_start"), py::arg("columns"), py::arg("values"),
          py::arg("patches") = py::none())
      .def(
          "apply",
          [](const PatchSmoother& self, const InArray& r, OutArray& y, double omega)
          {
            const auto n = static_cast<py::ssize_t>(self.num_rows());
            check_shape(r, {n}, "r");
            double* dst = out(y, {n}, "y");
            py::gil_scoped_release release;
            self.apply(r.data(), dst, omega);
          },
          py::arg("r"), py::arg("y").noconvert(), py::arg("omega"));
}
