"""The HX711 + Arduino sketch emulator (``sim://hx711``): the third-party sketches the
``line_regex`` driver's presets name (olkal/HX711_ADC, bogde/HX711 0.7.5 examples, bare
numbers), on the shared balance base of :mod:`labkit.emulators.balances`.
"""

from __future__ import annotations

from labkit.emulators.balances import BalanceEmulator, Pending, Tick
from labkit.emulators.base import register_emulator
from labkit.units import G0

HX711_BAUD = {"hx711_adc": 57600, "bogde": 57600, "bogde_full": 38400, "bare_float": 115200}
#: line rate of sketches slower than the ADC (bogde/HX711 0.7.5 examples): basic example
#: delay(1000) + one 10 SPS conversion; full example 11 conversions + delay(5000)
HX711_LINE_HZ = {"bogde": 1 / 1.1, "bogde_full": 1 / 6.2}
#: sketches that read the serial port (tare with ``t``); bogde's examples never do
HX711_TARES = frozenset({"hx711_adc", "bare_float"})
#: the HX711's 24-bit two's complement rails (datasheet: output saturates there) and the
#: emulated bridge's zero offset in counts
ADC_MAX, ADC_MIN, ADC_ZERO = 0x7FFFFF, -0x800000, 81234


@register_emulator
class Hx711SketchEmulator(BalanceEmulator):
    """An Arduino + HX711 running a third-party sketch (``preset``): boot banner, then one
    value line per conversion at ``rate_hz`` (10 SPS; bogde 1/1.1 Hz, bogde_full 1/6.2 Hz),
    ``t`` tares (not the bogde examples: they never read the port). With ``unit=raw`` it
    prints ADC counts (``calibration`` counts/g) that saturate at 0x7FFFFF / -0x800000.

    The ADC saturates in every mode: a load beyond the rail (about 19.8 kg at the default
    ``calibration`` of 420 counts/g; 4e6 counts/g puts it at 2.1 g) makes a calibrated
    sketch print the rail's constant value, as the real libraries do (no overload marker).
    Faults: ``overload`` (probability per line that the ADC sits at its positive rail),
    ``reset_at`` (the sketch reboots: banner again, tare at start-up with the load on the
    cell), ``stop_at`` (s after open: the sketch stops printing, the port stays open).
    """

    protocol = "hx711"
    default_rate_hz = 10.0

    def __post_init__(self) -> None:
        self.preset = str(self.options.get("preset", "hx711_adc"))
        if self.preset not in HX711_BAUD:
            raise ValueError(f"preset {self.preset!r}: known {', '.join(HX711_BAUD)}")
        self.default_rate_hz = HX711_LINE_HZ.get(self.preset, type(self).default_rate_hz)
        super().__post_init__()
        self.serial_settings = {"baudrate": HX711_BAUD[self.preset], "bytesize": 8,
                                "parity": "N", "stopbits": 1}
        self.calibration = float(self.options.get("calibration", 420.0))
        self.startup_s = float(self.options.get("startup_s", 1.0))
        self.tare_s = float(self.options.get("tare_s", 0.5))
        self._stream_from = 0.0

    def banner(self, t: float) -> None:
        self.streaming = False
        self._stream_from = t + self.startup_s
        if self.preset == "hx711_adc":
            self._queue(b"\r\nStarting...\r\n", t + 0.01)
            self._queue(b"Startup is complete\r\n", self._stream_from)
        elif self.preset == "bogde":  # HX711_basic_example: no banner at all
            pass
        elif self.preset == "bogde_full":  # HX711_full_example's setup(): numbers, no weights
            raw = int(round(self.to_unit(self.signal.last.gross_n) * self.calibration)) + ADC_ZERO
            self._queue(b"HX711 Demo\r\nInitializing the scale\r\nBefore setting up the scale:\r\n"
                        b"read: \t\t%d\r\nread average: \t\t%d\r\n" % (raw, raw), t + 0.01)
            self._queue(b"After setting up the scale:\r\nget units: \t\t0.0\r\nReadings:\r\n",
                        self._stream_from - 0.01)
        else:  # a minimal sketch: one line of text, then bare numbers
            self._queue(b"\r\nHX711 scale ready\r\n", t + 0.01)

    def on_tick(self, tick: Tick) -> None:
        if not self.streaming and tick.t >= self._stream_from:
            self.streaming = True
        for pending in list(self.pending):  # the sketch tares after its averaging settles
            if tick.t - pending.since >= self.tare_s:
                self.pending.remove(pending)
                self.tare_n = tick.gross_n - self.zero_n
                if self.preset == "hx711_adc":
                    self.reply(b"Tare complete\r\n", tick.t)
        if self.streaming:
            self.stream_line(tick)

    def next_output_time(self, t: float) -> float | None:
        base = super().next_output_time(t)
        nxt = self.signal.next_time()
        return nxt if base is None else min(base, nxt)

    def weigh(self, tick: Tick) -> tuple[str, float | None]:
        return "S", self.to_unit(tick.gross_n - self.zero_n - self.tare_n)

    def stream_line(self, tick: Tick) -> None:
        stop = self.faults.get("stop_at")
        if stop is not None and self.since_open(tick.t) >= stop:
            return  # switched off / cable pulled at the sketch's end: nothing more
        _, grams = self.weigh(tick)
        assert grams is not None
        counts = int(round(grams * self.calibration)) + ADC_ZERO
        saturated = not ADC_MIN < counts < ADC_MAX
        counts = max(ADC_MIN, min(ADC_MAX, counts))
        if self._chance("overload"):
            counts, saturated = ADC_MAX, True
        if self.unit == "raw" or self.preset == "bogde":  # the basic example prints scale.read()
            number = str(counts)
        else:
            if saturated:  # the sketch converts the railed code like any other
                grams = (counts - ADC_ZERO) / self.calibration
            number = f"{grams:.{self.decimals}f}"
        if self.preset == "hx711_adc":
            line = f"Load_cell output val: {number}"
        elif self.preset == "bogde":
            line = f"HX711 reading: {number}"
        elif self.preset == "bogde_full":
            line = f"one reading:\t{number}\t| average:\t{number}"
        else:
            line = number
        self.reply(line.encode("ascii") + b"\r\n", tick.t)

    def to_unit(self, newtons: float) -> float:
        return newtons / (1e-3 * G0)  # the sketch prints grams (or counts from grams)

    def command(self, line: bytes, t: float) -> None:
        pass  # sketches read single characters; see handle

    def handle(self, data: bytes, t: float) -> None:
        self.advance(t)
        if b"t" in data and self.preset in HX711_TARES:
            self.pending.append(Pending("T", t))
