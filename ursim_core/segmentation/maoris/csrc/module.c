/* The extension module ``_maoris_kernels``: every kernel of kernels.h (built by compiled.build_ahead). */
#define URSIM_MAORIS_MODULE_C
#include "kernels.h"

#define ENTRY(name) {#name, (PyCFunction)(void (*)(void))kernel_##name, METH_FASTCALL, NULL}

static PyMethodDef methods[] = {
    ENTRY(distance_transform), ENTRY(centre_rectangles), ENTRY(paint_discs), ENTRY(lookup_bytes),
    ENTRY(label_flat_zones), ENTRY(label_radii_zones_counted), ENTRY(zone_values_and_sizes), ENTRY(first_pixels),
    ENTRY(resolve_parents), ENTRY(relabel),
    ENTRY(build_adjacency), ENTRY(adjacency_entries), ENTRY(_link_entries), ENTRY(remove_small_zones),
    ENTRY(compact_graph), ENTRY(expand_graph),
    ENTRY(_compact_labels), ENTRY(count_contacts), ENTRY(join_counts), ENTRY(group_candidates), ENTRY(contact_table),
    ENTRY(merge_ripples), ENTRY(remove_doors),
    ENTRY(flood_levels), ENTRY(clearance_levels),
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "_maoris_kernels",
    "The MAORIS kernels in C (ursim_core/segmentation/maoris/csrc), a port of the numba kernels.", -1, methods,
};

PyMODINIT_FUNC PyInit__maoris_kernels(void)
{
    import_array();
    return PyModule_Create(&module);
}
