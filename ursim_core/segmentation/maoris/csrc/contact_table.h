/* Storage of the MAORIS contact counts (port of ../kernels/contact_table.py, which explains it).
 *
 * A count is kept per pair of zones (a, b): the contour pixels of a having b in their 3x3
 * neighbourhood. Each zone has a row of SLOTS int64 of its own ([overflow flag, then up to 7
 * entries (partner << 32) + count, -1 = free]); zones with more partners spill into a shared
 * hash table of int64 keys ``a * base + b``, open addressing with linear probing. The table's
 * ``meta`` holds [entries, bits, MEMO recently used keys, their MEMO slots].
 *
 * The row order of contact_table and every later probe depend on the exact hashing, growth and
 * memo of the numba code: they are reproduced as they are, not improved.
 */
#ifndef URSIM_MAORIS_CONTACT_TABLE_H
#define URSIM_MAORIS_CONTACT_TABLE_H

#include "common.h"

#define EMPTY (-1)
#define GOLDEN 0x9E3779B97F4A7C15ULL
#define MEMO 64
#define META_SIZE (2 + 2 * MEMO)
#define SLOTS 8
#define COUNT_MASK ((int64_t)0xFFFFFFFF)

/* The shared table: keys and counts of ``size`` slots (a power of two) and its meta. ``owned``:
 * keys and counts were allocated here (malloc), else they are a numpy array's. */
typedef struct {
    int64_t *keys, *counts, *meta;
    int64_t size;
    int owned;
} Table;

/* _new_table's keys and counts: 2**bits slots, owned. Returns 0, or -1 when out of memory. */
static inline int table_arrays(int64_t bits, Table *table)
{
    int64_t size = (int64_t)1 << bits;
    table->keys = filled_i64(size, EMPTY);
    table->counts = calloc((size_t)size, sizeof(int64_t));
    table->size = size;
    table->owned = 1;
    if (table->keys == NULL || table->counts == NULL) {
        free(table->keys);
        free(table->counts);
        table->keys = table->counts = NULL;
        return -1;
    }
    return 0;
}

/* _new_table: an empty table with 2**bits slots and its own meta. */
static inline int table_new(int64_t bits, Table *table)
{
    table->meta = filled_i64(META_SIZE, EMPTY);
    if (table->meta == NULL || table_arrays(bits, table) < 0) {
        free(table->meta);
        table->meta = NULL;
        return -1;
    }
    table->meta[0] = 0;
    table->meta[1] = bits;
    return 0;
}

/* _probe: the slot of ``key`` in ``keys`` (size slots), hashed on ``bits`` bits. A hash set
 * probed on fewer bits than its size (the fusions' scratch sets) still wraps at its size. */
static inline int64_t probe(const int64_t *keys, int64_t size, int64_t key, int64_t bits)
{
    int64_t mask = size - 1;
    int64_t slot = (int64_t)(((uint64_t)key * GOLDEN) >> (64 - bits));
    while (keys[slot] != EMPTY && keys[slot] != key) {
        slot = (slot + 1) & mask;
    }
    return slot;
}

static inline int64_t table_slot(Table *table, int64_t key)
{
    int64_t *meta = table->meta;
    int64_t memo = 2 + (key & (MEMO - 1));
    if (meta[memo] == key) {
        return meta[memo + MEMO];
    }
    int64_t slot = probe(table->keys, table->size, key, meta[1]);
    if (table->keys[slot] == key) {
        meta[memo] = key;
        meta[memo + MEMO] = slot;
    }
    return slot;
}

static inline int64_t table_get(Table *table, int64_t key)
{
    int64_t slot = table_slot(table, key);
    return table->keys[slot] == key ? table->counts[slot] : 0;
}

static inline void table_add(Table *table, int64_t key, int64_t delta)
{
    int64_t slot = table_slot(table, key);
    if (table->keys[slot] == key) {
        table->counts[slot] += delta;
    } else {
        table->keys[slot] = key;
        table->counts[slot] = delta;
        table->meta[0] += 1;
    }
}

/* _table_reserve: grow the table (a new, owned pair of arrays; the old ones freed if owned)
 * when ``more`` new keys could fill it over half. Returns 0, or -1 when out of memory (the
 * table is then left as it was). */
static inline int table_reserve(Table *table, int64_t more)
{
    int64_t *meta = table->meta;
    if (2 * (meta[0] + more) <= table->size) {
        return 0;
    }
    int64_t bits = meta[1];
    while (2 * (meta[0] + more) > ((int64_t)1 << bits)) {
        bits += 1;
    }
    Table grown;
    if (table_arrays(bits, &grown) < 0) {
        return -1;
    }
    for (int64_t old = 0; old < table->size; old++) {
        if (table->keys[old] != EMPTY) {
            int64_t slot = probe(grown.keys, grown.size, table->keys[old], bits);
            grown.keys[slot] = table->keys[old];
            grown.counts[slot] = table->counts[old];
        }
    }
    if (table->owned) {
        free(table->keys);
        free(table->counts);
    }
    table->keys = grown.keys;
    table->counts = grown.counts;
    table->size = grown.size;
    table->owned = 1;
    meta[1] = bits;
    for (int64_t i = 2; i < META_SIZE; i++) {
        meta[i] = EMPTY;
    }
    return 0;
}

static inline void table_release(Table *table)
{
    if (table->owned) {
        free(table->keys);
        free(table->counts);
        table->keys = table->counts = NULL;
        table->owned = 0;
    }
}

/* contact_get: count (a, b), from a's own row, else from the shared table. */
static inline int64_t contact_get(const int64_t *slots, Table *table, int64_t base, int64_t a, int64_t b)
{
    int64_t start = a * SLOTS;
    for (int64_t k = start + 1; k < start + SLOTS; k++) {
        int64_t entry = slots[k];
        if (entry >= 0 && (entry >> 32) == b) {
            return entry & COUNT_MASK;
        }
    }
    if (slots[start] != 0) {
        return table_get(table, a * base + b);
    }
    return 0;
}

/* _contact_add (parent NULL) and _contact_add_live (parent: the union-find parents; an entry
 * whose partner is a fused zone counts as free when the row has no free entry). */
static inline void contact_add(int64_t *slots, Table *table, int64_t base, int64_t a, int64_t b, int64_t delta,
                               const int32_t *parent)
{
    int64_t start = a * SLOTS;
    int64_t free_entry = -1;
    for (int64_t k = start + 1; k < start + SLOTS; k++) {
        int64_t entry = slots[k];
        if (entry >= 0) {
            if ((entry >> 32) == b) {
                entry += delta;
                slots[k] = (entry & COUNT_MASK) ? entry : -1;
                return;
            }
        } else if (free_entry == -1) {
            free_entry = k;
        }
    }
    if (slots[start] != 0) {
        int64_t key = a * base + b;
        int64_t slot = table_slot(table, key);
        if (table->keys[slot] == key) {
            table->counts[slot] += delta;
            return;
        }
    }
    if (free_entry == -1 && parent != NULL) {
        for (int64_t k = start + 1; k < start + SLOTS; k++) {
            int64_t partner = slots[k] >> 32;
            if (parent[partner] != partner) {
                free_entry = k;
                break;
            }
        }
    }
    if (free_entry != -1) {
        /* A new contact only ever starts with a positive count. */
        slots[free_entry] = (b << 32) + delta;
        return;
    }
    slots[start] = 1;
    table_add(table, a * base + b, delta);
}

#endif
