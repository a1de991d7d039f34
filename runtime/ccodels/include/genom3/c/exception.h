/* genom3/c/exception.h (genom2bip runtime): success, and the exceptions every component may raise.
 *
 * genom_ok is success (a null event).  genom_unkex carries a message for a failure the description does
 * not declare; genom_syserr carries an errno value; genom_fatal ends the component.
 */
#ifndef GENOM2BIP_GENOM3_C_EXCEPTION_H
#define GENOM2BIP_GENOM3_C_EXCEPTION_H

#include <stdint.h>

#include "genom3/c/event.h"
#include "genom3/c/context.h"

#define genom_ok ((genom_event)0)

const char genom_extern_weak genom_fatal[] = "::genom::fatal";

const char genom_extern_weak genom_unkex_id[] = "::genom::unkex";
typedef struct genom_unkex_detail {
  char what[128];
} genom_unkex_detail;

static inline genom_event genom_unkex(genom_unkex_detail *detail, genom_context self)
{
  return self->raise(genom_unkex_id, detail, sizeof(*detail), self);
}

const char genom_extern_weak genom_syserr_id[] = "::genom::syserr";
typedef struct genom_syserr_detail {
  int32_t code;
} genom_syserr_detail;

static inline genom_event genom_syserr(genom_syserr_detail *detail, genom_context self)
{
  return self->raise(genom_syserr_id, detail, sizeof(*detail), self);
}

#endif /* GENOM2BIP_GENOM3_C_EXCEPTION_H */
