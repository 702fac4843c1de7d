/* The coupling procedure of an array board ("heat one, read all"; PROTOCOL.md section 6):
 * every port's TSP read cold, heater `heater` on (dc, regulated) until settled, n scans of
 * every port through the sample window, then the cut and a scan of every port at each
 * log-spaced time. A scan reads port m at base + m * scan_us through the TSP multiplexer;
 * the first port of a window or curve scan is read by the single-heater states of st_core.c,
 * the rest here (state S_SCAN). Every sample of this procedure is an ARRAY_SAMPLE. */
#include <string.h>
#include "st_core_int.h"
#include "st_fixed.h"
#include "st_hal.h"

#define COLD_INTERVAL_US 100000UL /* between the cold scans */

uint8_t st_array_start(st_core_t *c, const uint8_t *b, uint8_t len)
{
    st_proc_t *p = &c->p;
    const st_board_t *bd = hal_board();
    uint32_t now = hal_now_us();
    if (len != ST_LEN_COUPLING) return ST_E_LENGTH;
    p->proc = ST_PROC_COUPLING;
    p->heater = b[0];
    p->ports = b[1];
    p->power_uw = st_get_u32(b + 2);
    p->settle_ms = st_get_u32(b + 6);
    p->window_us = st_get_u16(b + 10);
    p->n = st_get_u16(b + 12);
    p->t_first_us = st_get_u32(b + 14);
    p->t_last_ms = st_get_u32(b + 18);
    p->per_decade = b[22];
    p->interval_ms = 100;
    p->period_ns = 1000000U; /* dc */
    p->on_ns = p->period_ns;
    if (bd->ports < 2 || p->ports < 1 || p->ports > bd->ports || p->heater >= bd->ports ||
        p->power_uw == 0 || p->n == 0 || p->per_decade == 0 || p->t_first_us < 10 ||
        p->window_us < 10 || p->window_us > 4000 || p->t_last_ms > ST_CURVE_MAX_MS ||
        p->t_last_ms * 1000U < p->t_first_us || p->settle_ms > ST_SETTLE_MAX_MS)
        return ST_E_PARAM;
    p->total = st_log_count(p->t_first_us, p->per_decade, p->t_last_ms * 1000U);
    st_heater_off();
    hal_fixture_dac(0);
    hal_select_heater(p->heater);
    c->f_dropped = 0;
    p->t_start = now;
    p->t_clock = now;
    p->t_status = now + ST_STATUS_MS * 1000U;
    p->k = 0;
    st_array_scan(c, now + COLD_INTERVAL_US, 0, ST_KIND_COLD, COLD_INTERVAL_US, SCAN_COLD);
    return ST_OK;
}

/* Read ports first .. ports-1 at base + m * scan_us; `rel` is port 0's time as reported. */
void st_array_scan(st_core_t *c, uint32_t base, uint8_t first, uint8_t kind, uint32_t rel,
                   uint8_t then)
{
    st_proc_t *p = &c->p;
    p->scan_base = base;
    p->scan_rel = rel;
    p->scan_kind = kind;
    p->scan_then = then;
    p->port = first;
    hal_select_tsp(first);
    hal_adc_at(base + (uint32_t)first * hal_board()->scan_us);
    st_arm(c, kind);
    p->state = S_SCAN;
}

static void heat(st_core_t *c, uint32_t now)
{
    st_proc_t *p = &c->p;
    const st_board_t *bd = hal_board();
    uint32_t i_ua = st_current_for_power(p->power_uw, bd->vd_nominal_uv);
    hal_release();
    hal_heater_dac(st_dac_for_current(i_ua, bd->i_full_ua, bd->dac_max));
    hal_heater_pwm(p->period_ns, p->on_ns);
    p->t_start = now; /* settling counts from here, not from the cold scans */
    p->t_clock = now;
    p->run_ms = 0;
    p->run_us = 0;
    p->k = 0;
    p->t_next = now + ST_CONTROL_TICK_MS * 1000U;
    p->state = S_SETTLE;
}

/* S_SCAN: one port read; the next port, or what follows the scan. */
void st_array_step(st_core_t *c, uint32_t now)
{
    st_proc_t *p = &c->p;
    uint32_t scan = hal_board()->scan_us;
    if (!p->adc_ready) return;
    p->adc_armed = 0;
    st_record(c, p->scan_kind, p->scan_rel + (uint32_t)p->port * scan);
    if ((uint8_t)(p->port + 1u) < p->ports) {
        st_array_scan(c, p->scan_base, (uint8_t)(p->port + 1u), p->scan_kind, p->scan_rel,
                      p->scan_then);
        return;
    }
    p->port = 0;
    hal_select_tsp(0);
    switch (p->scan_then) {
    case SCAN_COLD:
        if (++p->k < p->n) {
            st_array_scan(c, p->scan_base + COLD_INTERVAL_US, 0, ST_KIND_COLD,
                          p->scan_rel + COLD_INTERVAL_US, SCAN_COLD);
        } else {
            heat(c, now);
        }
        break;
    case SCAN_STEADY:
        hal_release();
        p->k++;
        p->t_next = now + (uint32_t)p->interval_ms * 1000U;
        p->state = S_GAP;
        break;
    default: /* SCAN_CURVE: the next log time after this scan (early ones are skipped) */
        st_curve_next(c, p->scan_rel + (uint32_t)p->ports * scan);
        break;
    }
}
