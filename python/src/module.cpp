// The extension rgbl._rgbl; python/rgbl/__init__.py re-exports it as the package `rgbl`.

#include "common.hpp"

#include "rgbl/core/error.hpp"

#include <exception>
#include <string>

namespace rgbl::python {
namespace {

// Exception classes live for the whole process (the module is never unloaded).
PyObject* g_error = nullptr;
PyObject* g_config_error = nullptr;
PyObject* g_parse_error = nullptr;

PyObject* new_exception(py::module_& m, const char* name, const py::tuple& bases, const char* doc) {
  const std::string qualified = std::string("rgbl.") + name;
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
  if (type == nullptr) throw py::error_already_set();
  m.attr(name) = py::handle(type);
  return type;
}

// Raises `type(message)` with extra attributes (the key, the file and line) set on the instance.
void raise(PyObject* type, const char* message, const py::dict& attributes) {
  py::object instance = py::reinterpret_steal<py::object>(PyObject_CallFunction(type, "s", message));
  if (!instance) return;  // the call set an error already
  for (const auto& [key, value] : attributes) instance.attr(key) = value;
  PyErr_SetObject(type, instance.ptr());
}

}  // namespace

void bind_errors(py::module_& m) {
  g_error = new_exception(m, "Error", py::make_tuple(py::handle(PyExc_RuntimeError)),
                          "Base of the errors rgbl raises at its IO and configuration edges.");
  g_config_error = new_exception(
      m, "ConfigError", py::make_tuple(py::handle(g_error), py::handle(PyExc_ValueError)),
      "An option or settings key with a value that cannot work; `key` names it, the message says what it must be.");
  g_parse_error = new_exception(
      m, "ParseError", py::make_tuple(py::handle(g_error), py::handle(PyExc_OSError)),
      "A file that is missing, unreadable or not in the expected format; `file` and `line` (0 when the format "
      "has no lines) say where.");
  py::register_exception_translator([](std::exception_ptr error) {
    try {
      if (error) std::rethrow_exception(error);
    } catch (const ConfigError& e) {
      py::dict attributes;
      attributes["key"] = e.key();
      raise(g_config_error, e.what(), attributes);
    } catch (const ParseError& e) {
      py::dict attributes;
      attributes["file"] = e.file().string();
      attributes["line"] = e.line();
      raise(g_parse_error, e.what(), attributes);
    } catch (const Error& e) {
      PyErr_SetString(g_error, e.what());
    }
  });
}

}  // namespace rgbl::python

PYBIND11_MODULE(_rgbl, m) {
  namespace rp = rgbl::python;
  m.doc() = "rgbl: LiDAR-enhanced indirect visual SLAM (the C++ library's pipeline, numpy in and out).";
  // Types and functions take the module's name as theirs: the package's, so that help() and the
  // signatures say rgbl.System, not rgbl._rgbl.System. Restored below for the import system.
  m.attr("__name__") = "rgbl";
  m.attr("__version__") = RGBL_VERSION_STRING;
  rp::bind_errors(m);
  rp::bind_geometry(m);
  rp::bind_io(m);
  rp::bind_depth(m);
  rp::bind_features(m);
  rp::bind_eval(m);
  rp::bind_tracking(m);
  rp::bind_pipeline(m);
  rp::bind_sim(m);
  m.attr("__name__") = "rgbl._rgbl";
}
