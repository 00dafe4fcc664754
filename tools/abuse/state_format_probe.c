/* state_format.h as a shared library for the Python abuse tests
 * (tools/abuse/state_format.py), so that Python restates none of the format. */
#include "state_format.h"

#include <string.h>

size_t probe_header_size(void) { return sizeof(StateHeader); }
size_t probe_clock_size(void) { return offsetof(Snapshot, data); }

/* Where a field of the header or of the clock lies in a serialized state, by its
 * name in StateHeader or Clock (SIZE_MAX: no such field). */
size_t probe_offset(const char *field)
{
#define HEADER_FIELD(name) \
    if (strcmp(field, #name) == 0) return offsetof(StateHeader, name);
#define CLOCK_FIELD(name) \
    if (strcmp(field, #name) == 0) return sizeof(StateHeader) + offsetof(Clock, name);
    HEADER_FIELD(magic)
    HEADER_FIELD(version)
    HEADER_FIELD(reserved)
    HEADER_FIELD(size)
    HEADER_FIELD(guid_hash)
    HEADER_FIELD(checksum)
    CLOCK_FIELD(state)
    CLOCK_FIELD(stop_time_defined)
    CLOCK_FIELD(steps)
    CLOCK_FIELD(start_time)
    CLOCK_FIELD(stop_time)
    CLOCK_FIELD(comm_time)
#undef HEADER_FIELD
#undef CLOCK_FIELD
    return SIZE_MAX;
}

uint64_t probe_checksum(const unsigned char *serialized, size_t n)
{
    return state_checksum(serialized, n);
}
