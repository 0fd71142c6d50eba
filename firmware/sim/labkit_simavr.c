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
 *       OC1A <cycle of the rising edge> <cycle of the falling edge>
 * - A second pulse train on PB0 (Arduino pin 8, ICP1), the rotor's once-per-revolution
 *   pulse: active-low pulses, frequency in Hz, optionally ramping linearly in time
 *   (f = hz * (1 + ramp * seconds since the command)):
 *       icp <hz> ramp <relative change per s> low_us <pulse length>     (icp 0 ...: stop)
 *       glitch <fraction of the period> <low cycles>   one spurious pulse in the next period
 *   every falling edge is printed with the CPU cycle it was driven at:
 *       EDGE <cycle>        GLITCH <cycle>
 * - Every 10 simulated ms: CYCLE <cycle> (the simulated clock, for tests that wait on it).
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
#include "avr_timer.h"
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

/* ICP1 (PB0) generator, written by the stdin thread; icp_generation tells the
 * generator that new settings arrived (the ramp restarts from them) */
static avr_irq_t *icp_pin;
static volatile double icp_hz = 0.0;
static volatile double icp_ramp = 0.0;
static volatile double icp_low_us = 20.0;
static volatile int icp_generation = 0;
static volatile double glitch_fraction = 0.0;
static volatile int glitch_low_cycles = 0;
static volatile int glitch_requested = 0;
static int icp_seen_generation = 0;
static avr_cycle_count_t icp_t0 = 0;

static avr_timer_t *timer1;                 /* for the cycle corrections below */

#define ICR1_ADDR 0x86
#define OCR1A_ADDR 0x88
#define TCCR1A_ADDR 0x80

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
    static int ms = 0;
    if (++ms % 10 == 0) {                                   /* the simulated clock, for tests */
        printf("CYCLE %llu\n", (unsigned long long)when);
        fflush(stdout);
    }
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

static avr_cycle_count_t icp_high(avr_t *a, avr_cycle_count_t when, void *param) {
    (void)a; (void)when; (void)param;
    avr_raise_irq(icp_pin, 1);
    return 0;
}

static avr_cycle_count_t icp_glitch(avr_t *a, avr_cycle_count_t when, void *param) {
    (void)when; (void)param;
    avr_raise_irq(icp_pin, 0);
    printf("GLITCH %llu\n", (unsigned long long)a->cycle);
    fflush(stdout);
    avr_cycle_timer_register(a, glitch_low_cycles > 0 ? glitch_low_cycles : 1, icp_high, NULL);
    return 0;
}

/* One revolution of the rotor: a falling edge on ICP1 now, the next after 1/f(now). */
static avr_cycle_count_t icp_edge(avr_t *a, avr_cycle_count_t when, void *param) {
    (void)param;
    if (icp_generation != icp_seen_generation) {
        icp_seen_generation = icp_generation;
        icp_t0 = when;
    }
    double hz = icp_hz * (1.0 + icp_ramp * (double)(when - icp_t0) / a->frequency);
    if (hz <= 0.0)
        return when + avr_usec_to_cycles(a, 100);       /* stopped: look again in 100 us */
    avr_raise_irq(icp_pin, 0);
    /* simavr latches ICR1 at the instruction boundary after the edge (a->cycle, up to 4
     * cycles late); the hardware latches it at the edge itself (+ a fixed synchroniser
     * delay). Move the latched value back to the edge so the sketch sees what it would. */
    avr_cycle_count_t late = a->cycle - when;
    if (late && timer1 && timer1->tov_cycles == (avr_cycle_count_t)timer1->tov_top + 1) {
        uint16_t icr = a->data[ICR1_ADDR] | (a->data[ICR1_ADDR + 1] << 8);
        icr -= (uint16_t)late;
        a->data[ICR1_ADDR] = icr & 0xFF;
        a->data[ICR1_ADDR + 1] = icr >> 8;
    }
    printf("EDGE %llu\n", (unsigned long long)when);
    fflush(stdout);
    avr_cycle_timer_register_usec(a, (uint32_t)icp_low_us, icp_high, NULL);
    avr_cycle_count_t period = (avr_cycle_count_t)llround(a->frequency / hz);
    if (glitch_requested) {
        glitch_requested = 0;
        avr_cycle_timer_register(a, (avr_cycle_count_t)llround(glitch_fraction * period), icp_glitch,
                                 NULL);
    }
    return when + period;
}

/* The cycle of a change on OC1A. simavr applies a compare match at the instruction boundary
 * after it (up to 4 cycles late); the hardware at the timer tick itself. A change within 4
 * cycles after a compare match of OCR1A, with OC1A connected (COM1A != 0), is dated to the
 * match (prescaler 1); any other change (software) to the cycle it happened. */
static avr_cycle_count_t oc1a_cycle(void) {
    avr_cycle_count_t now = avr->cycle;
    if (!timer1 || timer1->tov_cycles != (avr_cycle_count_t)timer1->tov_top + 1 ||
        !(avr->data[TCCR1A_ADDR] & 0xC0))
        return now;
    uint16_t ocr = avr->data[OCR1A_ADDR] | (avr->data[OCR1A_ADDR + 1] << 8);
    avr_cycle_count_t match = timer1->tov_base + ocr + 1;
    if (match > now)
        match -= timer1->tov_cycles;
    return now - match <= 4 ? match : now;
}

/* simavr 1.6 applies the PWM-mode rule "clear on match => set at TOP, set on match => clear
 * at TOP" to a timer in normal mode (WGM 0) too, at every overflow; the hardware does not
 * (ATmega328P datasheet, Table 15-1: in normal mode COM1A only acts on compare matches).
 * Such a change of OC1A, at an overflow and against the compare mode, is undone one cycle
 * later and not recorded; each is reported as "FIXUP <cycle>". */
static avr_irq_t *oc1a_pin;
static unsigned long oc1a_fixups = 0;

static avr_cycle_count_t restore_oc1a(avr_t *a, avr_cycle_count_t when, void *param) {
    (void)a; (void)when;
    avr_raise_irq(oc1a_pin, (uint32_t)(uintptr_t)param);
    return 0;
}

static int overflow_artefact(uint32_t value) {
    if (!timer1 || timer1->wgm_op_mode_kind != avr_timer_wgm_normal)
        return 0;
    if (avr->cycle - timer1->tov_base > 4)
        return 0;
    int com = (avr->data[TCCR1A_ADDR] >> 6) & 3;
    return (com == 3 && value == 0) || (com == 2 && value != 0);
}

static void on_pwm_pin(struct avr_irq_t *irq, uint32_t value, void *param) {
    (void)irq; (void)param;
    if (overflow_artefact(value)) {
        oc1a_fixups++;
        printf("FIXUP %llu\n", (unsigned long long)avr->cycle);
        fflush(stdout);
        avr_cycle_timer_register(avr, 1, restore_oc1a, (void *)(uintptr_t)(value ? 0 : 1));
        return;
    }
    if (value && !pwm_high) {
        pwm_high = 1;
        pwm_rise = oc1a_cycle();
    } else if (!value && pwm_high) {
        pwm_high = 0;
        printf("OC1A %llu %llu\n", (unsigned long long)pwm_rise, (unsigned long long)oc1a_cycle());
        double width = avr_cycles_to_usec(avr, avr->cycle - pwm_rise);
        printf("PWM %.1f %.2f\n", (double)avr_cycles_to_usec(avr, avr->cycle), width);
        fflush(stdout);
    }
}

static void *read_commands(void *arg) {
    (void)arg;
    char line[256];
    while (fgets(line, sizeof line, stdin)) {
        double rpm, jitter, hz, ramp, low, fraction;
        int ppr, miss, cycles;
        if (strncmp(line, "quit", 4) == 0)
            break;
        if (sscanf(line, "icp %lf ramp %lf low_us %lf", &hz, &ramp, &low) == 3) {
            icp_low_us = low;
            icp_ramp = ramp;
            icp_hz = hz;
            icp_generation++;
            printf("OK %s", line);
        } else if (sscanf(line, "glitch %lf %d", &fraction, &cycles) == 2) {
            glitch_fraction = fraction;
            glitch_low_cycles = cycles;
            glitch_requested = 1;
            printf("OK %s", line);
        } else if (sscanf(line, "rpm %lf ppr %d jitter %lf miss %d", &rpm, &ppr, &jitter, &miss) == 4) {
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
    oc1a_pin = avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('B'), 1);
    avr_irq_register_notify(oc1a_pin, on_pwm_pin, NULL);
    icp_pin = avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('B'), 0);
    for (avr_io_t *io = avr->io_port; io; io = io->next)
        if (io->kind && strcmp(io->kind, "timer") == 0 && ((avr_timer_t *)io)->name == '1')
            timer1 = (avr_timer_t *)io;
    avr_raise_irq(icp_pin, 1);                             /* idle high (pull-up) */

    clock_gettime(CLOCK_MONOTONIC, &wall_start);
    avr_cycle_timer_register_usec(avr, 1000, pace, NULL);
    avr_cycle_timer_register_usec(avr, 1000, pulse_start, NULL);
    avr_cycle_timer_register_usec(avr, 1000, icp_edge, NULL);

    pthread_t reader;
    pthread_create(&reader, NULL, read_commands, NULL);

    int state = cpu_Running;
    while (!quit_requested && state != cpu_Done && state != cpu_Crashed)
        state = avr_run(avr);
    uart_pty_stop(&uart_pty);
    return state == cpu_Crashed ? 1 : 0;
}
