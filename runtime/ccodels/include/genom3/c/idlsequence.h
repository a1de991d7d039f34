/* genom3/c/idlsequence.h (genom2bip runtime): room in an unbounded IDL sequence.
 *
 * genom_sequence_reserve(s, n) makes s->_buffer hold n elements: the elements kept are copied (or the
 * buffer reallocated when it came from malloc), new ones are zero, s->_length is cut to n when larger,
 * s->_maximum becomes n and s->_release is free.  It returns 0, or -1 with errno ENOMEM.  n == 0 releases
 * the buffer.  The buffer may have come from anywhere: it is given back through s->_release.
 */
#ifndef GENOM2BIP_GENOM3_C_IDLSEQUENCE_H
#define GENOM2BIP_GENOM3_C_IDLSEQUENCE_H

#include <errno.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static inline int genom2bip_sequence_room(void **buffer, size_t esize, uint32_t want, uint32_t *length,
                                          uint32_t *maximum, void (**release)(void *))
{
  void *room;

  if (want == 0) {
    if (*buffer && *release) (*release)(*buffer);
    *buffer = NULL;
    *length = *maximum = 0;
    *release = NULL;
    return 0;
  }
  if (*buffer && *release == free) {
    room = realloc(*buffer, (size_t)want * esize);
    if (!room) { errno = ENOMEM; return -1; }
    if (want > *length) memset((char *)room + (size_t)*length * esize, 0, (size_t)(want - *length) * esize);
  } else {
    room = calloc(want, esize);
    if (!room) { errno = ENOMEM; return -1; }
    if (*buffer) {
      memcpy(room, *buffer, (size_t)(*length < want ? *length : want) * esize);
      if (*release) (*release)(*buffer);
    }
  }
  *buffer = room;
  *maximum = want;
  if (*length > want) *length = want;
  *release = free;
  return 0;
}

#define genom_sequence_reserve(s, n)                                                              \
  genom2bip_sequence_room((void **)&(s)->_buffer, sizeof(*(s)->_buffer), (uint32_t)(n),           \
                          &(s)->_length, &(s)->_maximum, &(s)->_release)

#endif /* GENOM2BIP_GENOM3_C_IDLSEQUENCE_H */
