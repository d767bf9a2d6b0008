/* The compact zone graph's records and its edge operations (../kernels/adjacency.py).
 *
 * A zone is a record of four int32 (HEAD, TAIL, DEGREE, VALUE); its neighbours form a doubly
 * linked list of node records of four int32 (NEIGHBOUR, NEXT, PREVIOUS, ATTRIBUTE), in
 * insertion order. A node's twin is ``node ^ 1``; the pair shares its edge attributes: the
 * minimum in the even node's ATTRIBUTE, unbreakability in the odd one's. Shared by the
 * adjacency kernels and the fusions (ripple merging, door removal), inlined into both.
 */
#ifndef URSIM_MAORIS_GRAPH_H
#define URSIM_MAORIS_GRAPH_H

#include <stdint.h>

#include "common.h"

enum { HEAD = 0, TAIL = 1, DEGREE = 2, VALUE = 3 };
enum { NEIGHBOUR = 0, NEXT = 1, PREVIOUS = 2, ATTRIBUTE = 3 };
/* constants.NO_MINIMUM: an edge's "lowest value met along fused paths" before any fusion. */
#define NO_MINIMUM (-1)

/* The two arrays of the graph tuple ``(records, nodes)``, both (n, 4) int32, C-contiguous. */
typedef struct {
    int32_t *records;
    int64_t n_records;
    int32_t *nodes;
    int64_t n_nodes;
} Graph;

#define REC(graph_records, zone, column) ((graph_records)[(int64_t)(zone) * 4 + (column)])
#define NODE(graph_nodes, node, column) ((graph_nodes)[(int64_t)(node) * 4 + (column)])

static inline void graph_append(int32_t *records, int32_t *nodes, int64_t zone, int64_t node, int64_t other)
{
    NODE(nodes, node, NEIGHBOUR) = (int32_t)other;
    NODE(nodes, node, NEXT) = -1;
    int64_t tail = REC(records, zone, TAIL);
    NODE(nodes, node, PREVIOUS) = (int32_t)tail;
    if (tail == -1) {
        REC(records, zone, HEAD) = (int32_t)node;
    } else {
        NODE(nodes, tail, NEXT) = (int32_t)node;
    }
    REC(records, zone, TAIL) = (int32_t)node;
    REC(records, zone, DEGREE) += 1;
}

static inline void graph_unlink(int32_t *records, int32_t *nodes, int64_t zone, int64_t node)
{
    int64_t before = NODE(nodes, node, PREVIOUS), after = NODE(nodes, node, NEXT);
    if (before == -1) {
        REC(records, zone, HEAD) = (int32_t)after;
    } else {
        NODE(nodes, before, NEXT) = (int32_t)after;
    }
    if (after == -1) {
        REC(records, zone, TAIL) = (int32_t)before;
    } else {
        NODE(nodes, after, PREVIOUS) = (int32_t)before;
    }
    REC(records, zone, DEGREE) -= 1;
}

/* Node (a -> b), or -1; walks the shorter of the two lists. */
static inline int64_t graph_find(const int32_t *records, const int32_t *nodes, int64_t a, int64_t b)
{
    if (REC(records, a, DEGREE) <= REC(records, b, DEGREE)) {
        int64_t node = REC(records, a, HEAD);
        while (node != -1) {
            if (NODE(nodes, node, NEIGHBOUR) == b) {
                return node;
            }
            node = NODE(nodes, node, NEXT);
        }
        return -1;
    }
    int64_t node = REC(records, b, HEAD);
    while (node != -1) {
        if (NODE(nodes, node, NEIGHBOUR) == a) {
            return node ^ 1;
        }
        node = NODE(nodes, node, NEXT);
    }
    return -1;
}

/* adjacency.fuse_edges: transfer the edges of ``zone`` to ``into`` (ZoneGraph.fuse, edges
 * only). A new edge (into, n) reuses the node pair of the edge (zone, n) it replaces, so the
 * node records never grow. */
static inline void graph_fuse_edges(int64_t zone, int64_t into, int32_t *records, int32_t *nodes)
{
    int64_t zone_value = REC(records, zone, VALUE);
    int64_t node = REC(records, zone, HEAD);
    while (node != -1) {
        int64_t following = NODE(nodes, node, NEXT);
        int64_t other = NODE(nodes, node, NEIGHBOUR);
        int64_t old_minimum = NODE(nodes, node & ~(int64_t)1, ATTRIBUTE);
        int64_t old_unbreakable = NODE(nodes, node | 1, ATTRIBUTE);
        graph_unlink(records, nodes, other, node ^ 1);
        if (other != into) {
            int64_t existing = graph_find(records, nodes, into, other);
            if (existing == -1) {
                int64_t new_minimum = (old_minimum == NO_MINIMUM || zone_value < old_minimum) ? zone_value : old_minimum;
                graph_append(records, nodes, into, node, other);
                graph_append(records, nodes, other, node ^ 1, into);
                NODE(nodes, node & ~(int64_t)1, ATTRIBUTE) = (int32_t)new_minimum;
                NODE(nodes, node | 1, ATTRIBUTE) = (int32_t)old_unbreakable;
            } else if (old_unbreakable) {
                NODE(nodes, existing | 1, ATTRIBUTE) = 1;
            }
        }
        node = following;
    }
    REC(records, zone, HEAD) = REC(records, zone, TAIL) = -1;
    REC(records, zone, DEGREE) = 0;
}

/* A graph argument: the tuple (records, nodes) of two (n, 4) int32 arrays. */
static int graph_arg(PyObject *obj, const char *what, Graph *graph)
{
    PyObject *const *items = tuple_arg(obj, 2, what);
    Array records, nodes;
    if (items == NULL || array_arg(items[0], NPY_INT32, 2, 0, what, &records)
        || array_arg(items[1], NPY_INT32, 2, 0, what, &nodes)) {
        return -1;
    }
    if (records.cols != 4 || nodes.cols != 4) {
        PyErr_Format(PyExc_TypeError, "%s: records and nodes must have 4 columns", what);
        return -1;
    }
    graph->records = records.data;
    graph->n_records = records.rows;
    graph->nodes = nodes.data;
    graph->n_nodes = nodes.rows;
    return 0;
}

#endif
