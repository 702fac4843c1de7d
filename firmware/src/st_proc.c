/* What every procedure of the core does, single heater or array (st_core.c, st_array.c):
 * record a reading into the FIFO, arm the ADC, turn the heater off, finish, and step a cooling
 * curve to its next log-spaced time. Below both procedure files: it calls neither. */
#include <string.h>
#include "st_core_int.h"
#include "st_fixed.h"
#include "st_hal.h"

void st_record(st_core_t *c, uint8_t kind, uint32_t t_us)
{
    st_raw_t *s;
    if (c->f_count >= ST_FIFO_LEN) {
        c->f_dropped++;
        return;
    }
    s = &c->fifo[(uint8_t)((c->f_head + c->f_count) % ST_FIFO_LEN)];
    s->kind = kind;
    s->port = c->p.proc == ST_PROC_COUPLING && kind == ST_KIND_POWER ? c->p.heater : c->p.port;
    s->t_us = t_us;
    memcpy(s->code, c->p.codes, sizeof s->code);
    if (c->p.n_samples == 0) {
        c->p.first_index = c->sample_index + c->f_count;
    }
    c->f_count++;
    c->p.n_samples++;
}

void st_heater_off(void)
{
    hal_heater_pwm(0, 0);
    hal_release();
    if (hal_board()->ports > 1) { /* an array board: back to its first heater and diode */
        hal_select_heater(0);
        hal_select_tsp(0);
    }
}

void st_arm(st_core_t *c, uint8_t kind)
{
    c->p.adc_armed = 1;
    c->p.adc_ready = 0;
    c->p.adc_kind = kind;
}

void st_finish(st_core_t *c, uint8_t status)
{
    if (c->p.proc != ST_PROC_CAL) {
        st_heater_off();
    }
    c->p.status = status;
    if (c->f_dropped && status == ST_OK) {
        c->p.status = ST_ERR_OVERFLOW;
    }
    c->p.state = S_IDLE;
}

void st_curve_next(st_core_t *c, uint32_t after_us)
{
    st_proc_t *p = &c->p;
    while (p->k < p->total && st_log_time_us(p->t_first_us, p->per_decade, p->k) < after_us) {
        p->k++;
    }
    if (p->k >= p->total) {
        st_finish(c, ST_OK);
        return;
    }
    hal_adc_at(p->t_cut + st_log_time_us(p->t_first_us, p->per_decade, p->k));
    st_arm(c, ST_KIND_CURVE);
    p->state = S_CURVE;
}
