/* Internals of the core shared by its files: st_core.c (commands, the five single-heater
 * procedures, FIFO, link), st_array.c (the coupling procedure of an array board) and st_proc.c
 * (what both do: record, arm, heater off, finish, the cooling curve's next reading). */
#ifndef ST_CORE_INT_H
#define ST_CORE_INT_H
#include <stdint.h>
#include "st_core.h"

enum {
    S_IDLE = 0,
    S_SETTLE,     /* heating (or waiting for the fixture) until settle_ms */
    S_POWER,      /* on-phase reading armed */
    S_WINDOW,     /* cut armed, reading at the end of the window */
    S_GAP,        /* between readings */
    S_CURVE,      /* cooling: log-spaced readings after the cut */
    S_CAL,        /* calibration readings */
    S_PULSE,      /* forward voltage: reading armed in a current pulse */
    S_SCAN        /* array board: reading the ports one after the other */
};

/* what follows a scan of the ports (st_proc_t.scan_then) */
enum { SCAN_COLD = 0, SCAN_STEADY, SCAN_CURVE };

/* st_proc.c */
void st_record(st_core_t *c, uint8_t kind, uint32_t t_us);
void st_arm(st_core_t *c, uint8_t kind);
void st_heater_off(void);
void st_finish(st_core_t *c, uint8_t status);
/* the cooling curve's next reading: the first log-spaced time at or after after_us (from the
 * cut), index k on; the procedure finishes after the last */
void st_curve_next(st_core_t *c, uint32_t after_us);

/* st_array.c */
uint8_t st_array_start(st_core_t *c, const uint8_t *b, uint8_t len);
void st_array_scan(st_core_t *c, uint32_t base, uint8_t first, uint8_t kind, uint32_t rel,
                   uint8_t then);
void st_array_step(st_core_t *c, uint32_t now);

#endif
