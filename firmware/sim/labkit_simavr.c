/* labkit_simavr.c - run a sketch's .hex on a simulated ATmega328P (simavr) for tests.
 *
 *   labkit_simavr <firmware.hex>
 *
 * - 16 MHz ATmega328P, the .hex loaded into flash at its addresses, run from reset.
 * - UART0 on a pseudo-terminal (simavr's uart_pty part); its path is printed first on stdout:
 *       PTY /dev/pts/N
 * - Simulated time is paced to wall-clock time (never ahead of it), so host time-outs and
 *   the sketch's millis() agree.
 * - Pulse trains on PD2 (Arduino pin 2, INT0): active-low pulses of 20 us. Commands on
 *   stdin, one per line, take effect at once:
 *       rpm <rpm> ppr <n> jitter <relative sd> miss <N>    (miss 0: none; else drop every Nth)
 *       quit
 * - Pulse widths on PB1 (Arduino pin 9, OC1A) printed on stdout, one line per pulse:
 *       PWM <t_us at the falling edge> <high time in us>
 *
 * Build: python3 firmware/build.py --harness. Used by tests/firmware/.
 */
#define _GNU_SOURCE
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "avr_ioport.h"
#include "sim_avr.h"
#include "sim_hex.h"
#include "sim_elf.h"
#include "sim_time.h"
#include "uart_pty.h"

#define PULSE_LOW_US 20

static avr_t *avr;
static uart_pty_t uart_pty;
static avr_irq_t *pulse_pin;

/* pulse generator settings, written by the stdin thread */
static volatile double gen_rpm = 0.0;
static volatile int gen_ppr = 1;
static volatile double gen_jitter = 0.0;
static volatile int gen_miss = 0;
static volatile int quit_requested = 0;
static unsigned long pulse_index = 0;
static unsigned int rng_state = 12345u;

static avr_cycle_count_t pwm_rise = 0;
static int pwm_high = 0;
static struct timespec wall_start;

static double uniform(void) {
    rng_state = rng_state * 1103515245u + 12345u;
    return ((rng_state >> 8) + 0.5) / 16777216.0;
}

static double gaussian(void) {
    return sqrt(-2.0 * log(uniform())) * cos(2.0 * M_PI * uniform());
}

static double wall_us(void) {
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    return (now.tv_sec - wall_start.tv_sec) * 1e6 + (now.tv_nsec - wall_start.tv_nsec) / 1e3;
}

/* Keep simulated time at or behind wall-clock time, checked every simulated millisecond. */
static avr_cycle_count_t pace(avr_t *a, avr_cycle_count_t when, void *param) {
    (void)param;
    double sim_us = avr_cycles_to_usec(a, when);
    double ahead = sim_us - wall_us();
    if (ahead > 200.0)
        usleep((useconds_t)ahead);
    return when + avr_usec_to_cycles(a, 1000);
}

static avr_cycle_count_t pulse_end(avr_t *a, avr_cycle_count_t when, void *param) {
    (void)a; (void)param;
    avr_raise_irq(pulse_pin, 1);
    return 0;
}

/* One period of the pulse train: a falling edge now (unless this pulse is "missing"). */
static avr_cycle_count_t pulse_start(avr_t *a, avr_cycle_count_t when, void *param) {
    (void)param;
    double rpm = gen_rpm;
    int ppr = gen_ppr > 0 ? gen_ppr : 1;
    if (rpm <= 0.0)
        return when + avr_usec_to_cycles(a, 1000);     /* stopped: look again in 1 ms */
    double period_us = 60e6 / (rpm * ppr);
    pulse_index++;
    int skip = gen_miss > 0 && pulse_index % (unsigned long)gen_miss == 0;
    if (!skip) {
        avr_raise_irq(pulse_pin, 0);
        avr_cycle_timer_register_usec(a, PULSE_LOW_US, pulse_end, NULL);
    }
    double next = period_us * (1.0 + gen_jitter * gaussian());
    if (next < 2.0 * PULSE_LOW_US)
        next = 2.0 * PULSE_LOW_US;
    return when + (avr_cycle_count_t)llround(next * a->frequency / 1e6);
}

static void on_pwm_pin(struct avr_irq_t *irq, uint32_t value, void *param) {
    (void)irq; (void)param;
    if (value && !pwm_high) {
        pwm_high = 1;
        pwm_rise = avr->cycle;
    } else if (!value && pwm_high) {
        pwm_high = 0;
        double width = avr_cycles_to_usec(avr, avr->cycle - pwm_rise);
        printf("PWM %.1f %.2f\n", (double)avr_cycles_to_usec(avr, avr->cycle), width);
        fflush(stdout);
    }
}

static void *read_commands(void *arg) {
    (void)arg;
    char line[256];
    while (fgets(line, sizeof line, stdin)) {
        double rpm, jitter;
        int ppr, miss;
        if (strncmp(line, "quit", 4) == 0)
            break;
        if (sscanf(line, "rpm %lf ppr %d jitter %lf miss %d", &rpm, &ppr, &jitter, &miss) == 4) {
            gen_ppr = ppr;
            gen_jitter = jitter;
            gen_miss = miss;
            gen_rpm = rpm;
            printf("OK %s", line);
        } else {
            printf("ERR %s", line);
        }
        fflush(stdout);
    }
    quit_requested = 1;
    return NULL;
}

static int load_hex(const char *path, elf_firmware_t *f) {
    ihex_chunk_p chunks = NULL;
    int count = read_ihex_chunks(path, &chunks);
    if (count <= 0)
        return -1;
    for (int i = 0; i < count; i++) {
        if (chunks[i].baseaddr < 1024 * 1024) {           /* flash, not eeprom */
            f->flash = chunks[i].data;
            f->flashsize = chunks[i].size;
            f->flashbase = chunks[i].baseaddr;
        }
    }
    return f->flash ? 0 : -1;
}

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: labkit_simavr <firmware.hex>\n");
        return 2;
    }
    elf_firmware_t f;
    memset(&f, 0, sizeof f);
    if (load_hex(argv[1], &f) != 0) {
        fprintf(stderr, "labkit_simavr: cannot read %s as Intel hex\n", argv[1]);
        return 2;
    }
    strcpy(f.mmcu, "atmega328p");
    f.frequency = 16000000;
    avr = avr_make_mcu_by_name(f.mmcu);
    if (!avr) {
        fprintf(stderr, "labkit_simavr: simavr has no atmega328p\n");
        return 2;
    }
    avr_init(avr);
    avr_load_firmware(avr, &f);
    avr->frequency = f.frequency;

    uart_pty_init(avr, &uart_pty);
    uart_pty_connect(&uart_pty, '0');
    printf("PTY %s\n", uart_pty.port[0].slavename);
    fflush(stdout);

    pulse_pin = avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('D'), 2);
    avr_raise_irq(pulse_pin, 1);                           /* idle high (pull-up) */
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('B'), 1), on_pwm_pin, NULL);

    clock_gettime(CLOCK_MONOTONIC, &wall_start);
    avr_cycle_timer_register_usec(avr, 1000, pace, NULL);
    avr_cycle_timer_register_usec(avr, 1000, pulse_start, NULL);

    pthread_t reader;
    pthread_create(&reader, NULL, read_commands, NULL);

    int state = cpu_Running;
    while (!quit_requested && state != cpu_Done && state != cpu_Crashed)
        state = avr_run(avr);
    uart_pty_stop(&uart_pty);
    return state == cpu_Crashed ? 1 : 0;
}
