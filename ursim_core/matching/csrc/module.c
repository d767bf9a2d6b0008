/* The extension module ``_matching_kernels``: every kernel of kernels.h (built by
 * ursim_core.matching.kernels with ursim_core.native). */
#include "kernels.h"

#define ENTRY(name) {#name, (PyCFunction)(void (*)(void))kernel_##name, METH_FASTCALL, NULL}

static PyMethodDef methods[] = {
    ENTRY(planar_match),
    ENTRY(planar_sweep),
    ENTRY(fit_axes),
    ENTRY(overlap_search),
    ENTRY(region_correspondences),
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "_matching_kernels",
    "The matcher's loops in C (ursim_core/matching/csrc): the planar matcher's seed-and-expand loop, "
    "a port of planar.py, at one m or over a sweep of m; the refit's fit of a scale and shift per axis; "
    "the orientation overlap's search; the regions one segmentation's regions overlap most in others.",
    -1, methods,
};

PyMODINIT_FUNC PyInit__matching_kernels(void)
{
    return PyModule_Create(&module);
}
