// labkit_strobe_host.h - the host side of labkit_strobe.ino: commands, status lines, the
// uptime clock (protocol: docs/reference/devices-strobe.md). Included once, by the sketch, after the
// timing code whose variables it reads; kept apart so each file stays readable.

uint32_t incForPeriod = 0;             // the period the increment was computed for

// m + dphi for the last period, dphi = D m T / (1 - D T): the rotor angle at the flashes
// advances by D revolutions per second. Done here, not in the capture interrupt (a float
// division is ~30 us on the AVR); it lags the period by one loop pass at most.
void updateIncrement(bool force) {
  noInterrupts();
  uint32_t T = periodTicks;
  float D = offsetHz;
  byte m = divider;
  interrupts();
  if (T == 0 || (T == incForPeriod && !force)) return;
  incForPeriod = T;
  float ts = (float)T / TICKS_PER_S;
  float dphi = D * m * ts / (1.0f - D * ts);
  bool ok = dphi <= 0.25f && dphi >= -0.25f;
  byte whole = m;
  uint32_t frac = 0;
  if (ok && dphi >= 0) {
    frac = (uint32_t)(dphi * 4294967296.0f);
  } else if (ok) {
    whole = m - 1;
    frac = 0UL - (uint32_t)(-dphi * 4294967296.0f);
  }
  noInterrupts();
  rangeOk = ok;
  incWhole = whole;
  incFrac = frac;
  interrupts();
}

// Milliseconds since boot from the extended Timer1 count (called often enough by loop():
// the count wraps every 268 s).
uint32_t lastUptimeTicks = 0;
uint32_t uptimeRemainder = 0;
uint32_t uptimeMsCount = 0;

uint32_t uptimeMs() {
  noInterrupts();
  uint32_t now = nowTicks();
  interrupts();
  uptimeRemainder += now - lastUptimeTicks;
  lastUptimeTicks = now;
  uptimeMsCount += uptimeRemainder / 16000UL;
  uptimeRemainder %= 16000UL;
  return uptimeMsCount;
}

void printBanner() {
  Serial.print(F("# labkit-strobe " VERSION " offset="));
  Serial.print(offsetHz, 3);
  Serial.print(F(" width="));
  Serial.print(widthTicks / 16);
  Serial.print(F(" div="));
  Serial.print(divider);
  Serial.print(F(" rate="));
  Serial.print(rateHz);
  Serial.print('\n');
}

void reply(const __FlashStringHelper *text) { Serial.print(text); Serial.print('\n'); }

// After OFFSET or DIV the status window's strobe frequency counts only the new flashes, so
// that f_rot - m * f_strobe is the new offset from the next line on (interrupts off).
void restartStrobeWindow() {
  winFlashes = 0;
  winFlashTicks = 0;
  lastFlashValid = false;
}

void handleCommand(char *cmd) {
  if (strcmp(cmd, "ID?") == 0) { reply(F("ID labkit-strobe " VERSION)); return; }
  if (strcmp(cmd, "OFF") == 0 || strcmp(cmd, "ON") == 0) {
    noInterrupts();
    lampOn = cmd[1] == 'N';
    if (!lampOn) cancelFlash();
    interrupts();
    reply(F("OK"));
    return;
  }
  char *space = strchr(cmd, ' ');
  if (space == NULL) { reply(F("ERR unknown command")); return; }
  *space = '\0';
  char *arg = space + 1;
  char *end;
  double value = strtod(arg, &end);
  if (end == arg || *end != '\0') { reply(F("ERR bad value")); return; }
  if (strcmp(cmd, "OFFSET") == 0) {
    if (value < -100.0 || value > 100.0) { reply(F("ERR bad value")); return; }
    noInterrupts(); offsetHz = value; restartStrobeWindow(); interrupts();
    updateIncrement(true);
  } else if (strcmp(cmd, "WIDTH") == 0) {
    if (value < 1 || value > 1000 || value != (long)value) { reply(F("ERR bad value")); return; }
    noInterrupts(); widthTicks = (uint16_t)value * 16; interrupts();
  } else if (strcmp(cmd, "DIV") == 0) {
    if (value < 1 || value > 100 || value != (long)value) { reply(F("ERR bad value")); return; }
    noInterrupts(); divider = (byte)value; restartStrobeWindow(); interrupts();
    updateIncrement(true);
  } else if (strcmp(cmd, "RATE") == 0) {
    if (value < 1 || value > 50 || value != (long)value) { reply(F("ERR bad value")); return; }
    rateHz = (unsigned int)value;
    nextStatusMs = uptimeMs() + 1000 / rateHz;
  } else {
    reply(F("ERR unknown command"));
    return;
  }
  reply(F("OK"));
}

void readCommands() {
  while (Serial.available()) {
    char c = Serial.read();
    if (c == '\r') continue;
    if (c == '\n') {
      line[lineLen] = '\0';
      if (lineLen) handleCommand(line);
      lineLen = 0;
    } else if (lineLen < sizeof(line) - 1) {
      line[lineLen++] = c;
    } else {
      lineLen = 0;
    }
  }
}

// n periods in sum ticks as Hz with 4 decimals ("0.0000" when none)
void printHz(uint16_t n, uint32_t sum) {
  if (n == 0 || sum == 0) { Serial.print(F("0.0000")); return; }
  uint64_t e4 = ((uint64_t)16000000ULL * 10000ULL * n + sum / 2) / sum;
  uint32_t whole = (uint32_t)(e4 / 10000ULL);
  uint16_t frac = (uint16_t)(e4 % 10000ULL);
  Serial.print(whole);
  Serial.print('.');
  if (frac < 1000) Serial.print('0');
  if (frac < 100) Serial.print('0');
  if (frac < 10) Serial.print('0');
  Serial.print(frac);
}

void printStatus() {
  noInterrupts();
  uint16_t revs = winRevs, flashes = winFlashes;
  uint32_t revTicks = winRevTicks, flashTicks = winFlashTicks, phase = lastPhase;
  byte flagBits = winFlags;
  bool isLocked = locked, pulses = haveEdge, lamp = lampOn;
  winRevs = 0; winRevTicks = 0; winFlashes = 0; winFlashTicks = 0;
  winFlags = pulses ? 0 : F_NOPULSE;
  interrupts();

  char flags[12];
  byte f = 0;
  if (!pulses || (flagBits & F_NOPULSE)) flags[f++] = 'Z';
  if (!isLocked || (flagBits & F_UNLOCKED)) flags[f++] = 'L';
  if (flagBits & F_NOISE) flags[f++] = 'N';
  if (!lamp) flags[f++] = 'X';
  if (flagBits & F_WIDTH) flags[f++] = 'W';
  if (flagBits & F_RANGE) flags[f++] = 'R';
  if (flagBits & F_SPEED) flags[f++] = 'O';
  if (flagBits & F_MISSED) flags[f++] = 'M';
  if (flagBits & F_LATE) flags[f++] = 'S';
  flags[f] = '\0';
  uint16_t tenths = (uint16_t)(((phase >> 16) * 3600UL + 32768UL) >> 16);
  if (tenths >= 3600) tenths = 0;

  Serial.print(F("S,"));
  Serial.print(seq++);
  Serial.print(',');
  Serial.print(uptimeMs());
  Serial.print(',');
  printHz(revs, revTicks);
  Serial.print(',');
  printHz(flashes, flashTicks);
  Serial.print(',');
  Serial.print(tenths / 10);
  Serial.print('.');
  Serial.print(tenths % 10);
  Serial.print(',');
  if (f == 0) Serial.print('0'); else Serial.print(flags);
  Serial.print('\n');
}
