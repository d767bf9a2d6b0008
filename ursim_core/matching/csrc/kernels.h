/* The matcher's C kernels (module.c lists them), each a METH_FASTCALL function of the module
 * ``_matching_kernels`` built by ursim_core.matching.kernels. */
#ifndef URSIM_MATCHING_KERNELS_H
#define URSIM_MATCHING_KERNELS_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>

#define KERNEL(name) PyObject *kernel_##name(PyObject *self, PyObject *const *args, Py_ssize_t nargs)

/* A C-contiguous buffer of a given item size and format kind ('i' signed int, 'f' float, 'b' bool/uint8). */
static inline int get_buffer(PyObject *obj, Py_ssize_t itemsize, char kind, int ndim, const char *what, Py_buffer *view)
{
    if (PyObject_GetBuffer(obj, view, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) {
        PyErr_Format(PyExc_TypeError, "%s must be a C-contiguous array", what);
        return -1;
    }
    const char *format = view->format ? view->format : "B";
    while (*format == '<' || *format == '=' || *format == '@' || *format == '|') {
        format++;
    }
    int kind_ok = (kind == 'i' && (*format == 'i' || *format == 'l' || *format == 'q'))
                  || (kind == 'f' && *format == 'd') || (kind == 'b' && (*format == '?' || *format == 'B'));
    if (view->itemsize != itemsize || !kind_ok || view->ndim != ndim) {
        PyErr_Format(PyExc_TypeError, "%s has the wrong type or shape (format %s, %d dimensions)", what,
                     view->format ? view->format : "B", view->ndim);
        PyBuffer_Release(view);
        return -1;
    }
    return 0;
}

/* planar.c */
KERNEL(planar_match);

#endif
