--[[
ardupilot_sysid.lua: a manoeuvre designed by `aeroident design`, played on ArduPlane as offsets
on the surface outputs about the command the pilot or the autopilot holds (docs/export.md,
"aeroident design"). Lua 5.3, ArduPilot's scripting API.

@DESCRIPTION@

To fly: copy to APM/scripts on the SD card, set SCR_ENABLE = 1, reboot; "aeroident: loaded"
appears on the GCS. Trim the aircraft at the design's condition (MANUAL flies the open-loop
response the design predicted), then @START@. The table plays once, from its first row, as
long as the vehicle stays armed; @STOP@ ends it at once, and the outputs return to what the
vehicle commands within OVERRIDE_MS. Start again only after a stop.

Each row's offset is in centidegrees of surface deflection in aeroident's sign convention
(de > 0 trailing edge down, da > 0 a negative rolling moment, dr > 0 trailing edge left).
ArduPlane's scaled outputs are positive for a positive body moment (aileron: roll right,
elevator: pitch up, rudder: yaw right) with +-4500 at full throw, so the offset becomes
  scaled = SIGN * centidegrees * 4500 / THROW_CDEG   (SIGN = -1 for all three)
and the command is the vehicle's own scaled output for the surface's function
(SRV_Channels:get_output_scaled) plus it. Every output whose SERVOn_FUNCTION is that function
gets the command as PWM through its SERVOn_MIN, _TRIM, _MAX and _REVERSED, as ArduPilot's
SRV_Channel::pwm_from_angle converts it, written as an override that lapses OVERRIDE_MS after
the last write (SRV_Channels:set_output_pwm_chan_timeout): if the script stops, the vehicle's
outputs come back by themselves. Mixed surfaces (elevons, V-tail, flaperons) are not played.

The row is the one due at the time since the start (millis): a late call plays the row then
due, so the record never stretches. Logged at every call as AIDI: TMs (ms since the start),
Row (0-based), and per surface its offset in centidegrees (<S>C) and the commanded scaled
output (<S>S); RCOU holds the PWM actually sent.

The rate is checked, since ArduPilot promises scripts no schedule: PERIOD_MS is the least
delay before the next call, and a busy autopilot calls later, so rows are skipped and the
record is a coarser manoeuvre than the one designed. While playing, the script counts the
rows played against the rows due and keeps the largest gap between two calls. The record is
not the designed manoeuvre when more than SKIP_FRACTION (5 %) of the ROWS rows are skipped, or
when two calls are more than GAP_PERIODS (2) table periods apart (a hole of a whole row or
more); then "aeroident: behind: ..." goes to the GCS at once as a warning, once per start. It
keeps playing: the AIDI log says which rows were flown, and the record is still a usable
manoeuvre, only not the designed one. At the end (finished, switched off or disarmed) the GCS
gets "aeroident: played P of ROWS rows at H Hz" (H: calls per second while playing) and, when
behind, "aeroident: not the designed manoeuvre"; the log gets one AIDR: Rows (ROWS), Due (rows
due by the end), Played, Hz, GapMs (the largest gap) and Slow (1 when behind).
]]

local RATE_HZ = @RATE_HZ@
local ROWS = @ROWS@
local ARM_RC = @ARM_RC@ -- RC input channel of the start switch; 0: the SCR_USER1 parameter
local PERIOD_MS = @PERIOD_MS@
local OVERRIDE_MS = @OVERRIDE_MS@
local IDLE_MS = 100
local SWITCH_HIGH_US = 1800
local SCALED_FULL = 4500
local MAV_INFO, MAV_WARNING = 6, 4
-- behind the design (header): more than this fraction of the ROWS rows skipped (a fraction of
-- the whole table, not of the rows due so far, which would call one early skip 33 %), ...
local SKIP_FRACTION = 0.05
-- ... or two calls more than this many table periods apart
local GAP_PERIODS = 2

local SURFACES = {
@SURFACES@
}

-- waiting: for the start switch to be low (at boot too, so a switch left high never starts
-- the manoeuvre by itself); ready: for it to go high; playing; done: for it to go low again
local state = 'waiting'
local t0_ms = 0
-- the calls' pace while playing: calls, rows played, the last row played, the first and last
-- call's ms since the start, the largest gap between calls (ms), whether the warning was sent
local pace = {}

local function start_on()
  if ARM_RC > 0 then
    local pwm = rc:get_pwm(ARM_RC)
    return pwm ~= nil and pwm > SWITCH_HIGH_US
  end
  local v = param:get('SCR_USER1')
  return v ~= nil and v > 0.5
end

-- every output channel of servo function `func`, with its PWM limits
local function outputs_of(func)
  local found = {}
  for ch = 1, 32 do
    local f = param:get('SERVO' .. ch .. '_FUNCTION')
    if f == nil then
      break
    end
    if math.floor(f + 0.5) == func then
      local p = 'SERVO' .. ch
      found[#found + 1] = {
        chan = ch - 1,
        min = param:get(p .. '_MIN'),
        trim = param:get(p .. '_TRIM'),
        max = param:get(p .. '_MAX'),
        reversed = param:get(p .. '_REVERSED') ~= 0,
      }
    end
  end
  return found
end

-- ArduPilot's SRV_Channel::pwm_from_angle for an angle output of range SCALED_FULL
local function pwm_of(o, scaled)
  if o.reversed then
    scaled = -scaled
  end
  scaled = math.max(-SCALED_FULL, math.min(SCALED_FULL, scaled))
  -- parameters are floats: the PWM is made an integer as ArduPilot's uint16_t is
  if scaled > 0 then
    return math.floor(o.trim + math.floor(scaled * (o.max - o.trim) / SCALED_FULL))
  end
  return math.floor(o.trim - math.floor(-scaled * (o.trim - o.min) / SCALED_FULL))
end

-- hands every output back to the vehicle (a zero timeout ends the override)
local function release()
  for _, s in ipairs(SURFACES) do
    for _, o in ipairs(s.outputs or {}) do
      local base = SRV_Channels:get_output_scaled(s.func) or 0
      SRV_Channels:set_output_pwm_chan_timeout(o.chan, pwm_of(o, base), 0)
    end
  end
end

local function find_outputs()
  for _, s in ipairs(SURFACES) do
    s.outputs = outputs_of(s.func)
    if #s.outputs == 0 then
      gcs:send_text(MAV_WARNING, string.format('aeroident: no SERVOn_FUNCTION = %d (%s)', s.func, s.name))
      return false
    end
  end
  return true
end

local function play(row, elapsed_ms)
  local values = { elapsed_ms, row }
  for _, s in ipairs(SURFACES) do
    local cdeg = s.offsets_cdeg[row + 1]
    local base = SRV_Channels:get_output_scaled(s.func) or 0
    local scaled = base + s.sign * cdeg * SCALED_FULL / s.throw_cdeg
    for _, o in ipairs(s.outputs) do
      SRV_Channels:set_output_pwm_chan_timeout(o.chan, pwm_of(o, scaled), OVERRIDE_MS)
    end
    values[#values + 1] = cdeg
    values[#values + 1] = scaled
  end
  logger:write('AIDI', @LOG_LABELS@, @LOG_FORMAT@, table.unpack(values))
end

-- counts a call `elapsed_ms` after the start, the switch-off and the finishing calls too (a
-- late one of those is a gap in the record as much as any)
local function count_call(elapsed_ms)
  if pace.calls > 0 then
    pace.gap_ms = math.max(pace.gap_ms, elapsed_ms - pace.last_ms)
  else
    pace.first_ms = elapsed_ms
  end
  pace.calls = pace.calls + 1
  pace.last_ms = elapsed_ms
end

local function count_row(row)
  if row ~= pace.row then
    pace.played = pace.played + 1
    pace.row = row
  end
end

-- calls per second while playing
local function achieved_hz()
  local span_ms = pace.last_ms - pace.first_ms
  if pace.calls < 2 or span_ms <= 0 then
    return 0.0
  end
  return (pace.calls - 1) * 1000 / span_ms
end

-- warns, once per start, when the calls fell behind the design (header), `due` rows being due
local function check_pace(due)
  local skipped = due - pace.played
  local late = skipped > SKIP_FRACTION * ROWS or pace.gap_ms > GAP_PERIODS * 1000 / RATE_HZ
  if late and not pace.warned then
    pace.warned = true
    gcs:send_text(MAV_WARNING, string.format('aeroident: behind: rows skipped %d, gap %d ms', skipped, pace.gap_ms))
  end
end

-- the end of a played record: its pace to the log and the GCS, `due` rows having been due
local function report(due)
  check_pace(due)
  local hz = achieved_hz()
  logger:write('AIDR', 'Rows,Due,Played,Hz,GapMs,Slow', 'IIIfII', ROWS, due, pace.played, hz, pace.gap_ms,
    pace.warned and 1 or 0)
  local severity = pace.warned and MAV_WARNING or MAV_INFO
  gcs:send_text(severity, string.format('aeroident: played %d of %d rows at %.1f Hz', pace.played, ROWS, hz))
  if pace.warned then
    gcs:send_text(MAV_WARNING, 'aeroident: not the designed manoeuvre')
  end
end

-- `after`: 'ready' when the switch is already off, else 'done' (it must go off first); `due`:
-- the rows due by now
local function stop(why, after, due)
  release()
  gcs:send_text(MAV_INFO, 'aeroident: ' .. why)
  report(due)
  state = after
end

-- the start switch on and armed: playing from now, or 'done' when an output is missing
local function begin()
  if not find_outputs() then
    state = 'done'
    return false
  end
  t0_ms = millis():tofloat()
  pace = { calls = 0, played = 0, row = -1, first_ms = 0, last_ms = 0, gap_ms = 0, warned = false }
  state = 'playing'
  gcs:send_text(MAV_INFO, 'aeroident: manoeuvre started')
  return true
end

local function update()
  local on = start_on()
  if state == 'waiting' or state == 'done' then
    if not on then
      state = 'ready'
    end
    return update, IDLE_MS
  end
  if state == 'ready' and not (on and arming:is_armed() and begin()) then
    return update, IDLE_MS
  end
  local elapsed_ms = math.floor(millis():tofloat() - t0_ms)
  count_call(elapsed_ms)
  local row = math.floor(elapsed_ms * RATE_HZ / 1000 + 1e-9)
  if not on then
    stop('manoeuvre stopped by the switch', 'ready', math.min(row, ROWS))
    return update, IDLE_MS
  end
  if not arming:is_armed() then
    stop('manoeuvre stopped: disarmed', 'done', math.min(row, ROWS))
    return update, IDLE_MS
  end
  if row >= ROWS then
    stop('manoeuvre finished', 'done', ROWS)
    return update, IDLE_MS
  end
  play(row, elapsed_ms)
  count_row(row)
  check_pace(row + 1)
  return update, PERIOD_MS
end

gcs:send_text(MAV_INFO, 'aeroident: loaded, ' .. ROWS .. ' rows at ' .. RATE_HZ .. ' Hz')

return update, IDLE_MS
