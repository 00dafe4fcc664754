/* The serialized FMU state, the one statement of its format: the instance core
 * writes and reads it, the fuzz targets and the abuse tests forge it.
 *
 * Native byte order, valid for the same binary:
 *   StateHeader | Snapshot (the Clock, then the model's data block)
 * The header's checksum is STATE_FNV1A over everything after the header; it is
 * unkeyed (anyone can recompute it), so a restored state is also checked field
 * by field. */
#ifndef STATE_FORMAT_H
#define STATE_FORMAT_H

#include <stddef.h>
#include <stdint.h>

#include "instance.h"

#define STATE_VERSION 2u /* 2: the work budget variables in every model */

typedef struct {
    char magic[8]; /* the FMI version's (InstanceApi.state_magic) */
    uint32_t version;
    uint32_t reserved; /* 0 */
    uint64_t size;     /* of the whole serialized state */
    uint64_t guid_hash;
    uint64_t checksum;
} StateHeader;

/* An FMU state: a snapshot of the clock and the model data block. */
struct Snapshot {
    Clock clock;
    unsigned char data[]; /* MODEL_DESCRIPTOR.data_size bytes */
};

#define STATE_FNV_OFFSET 14695981039346656037ull

/* 64-bit FNV-1a of n bytes, continuing from hash (STATE_FNV_OFFSET to start). */
static inline uint64_t state_fnv1a(const void *bytes, size_t n, uint64_t hash)
{
    const unsigned char *p = bytes;
    for (size_t i = 0; i < n; ++i) hash = (hash ^ p[i]) * 1099511628211ull;
    return hash;
}

/* The checksum a serialized state of total size n carries. */
static inline uint64_t state_checksum(const unsigned char *serialized, size_t n)
{
    return n < sizeof(StateHeader)
               ? 0
               : state_fnv1a(serialized + sizeof(StateHeader), n - sizeof(StateHeader),
                             STATE_FNV_OFFSET);
}

#endif
