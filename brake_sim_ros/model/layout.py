"""Index layout shared by the compiled kernels and their Python callers.

The kernels take plain float64 arrays; this module names every slot so that no caller
writes a bare number.
"""

from __future__ import annotations

# --- packed parameter vector -------------------------------------------------------
P_FLYWHEEL_INERTIA = 0
P_DRUM_INERTIA = 1
P_COUPLING_STIFFNESS = 2
P_COUPLING_DAMPING = 3
P_DRUM_RADIUS = 4
P_CONTACT_STIFFNESS = 5
P_CONTACT_DAMPING = 6
P_FRICTION_COEFFICIENT = 7
P_FRICTION_SMOOTHING_SPEED = 8
P_RIGID_COUPLING = 9  # 1.0: flywheel and drum move as one body (no torsional mode)
SIDES = ("left", "right")  # the shoes, in slot and column order: leading, trailing
P_SHOE_BASE = 12  # first slot of the left shoe; the right shoe follows at +SHOE_STRIDE
SHOE_STRIDE = 32

# offsets inside one shoe's block (world frame, shoe at its symmetric rest angle)
S_SIGN = 0  # +1 left (outward = counter-clockwise), -1 right (outward = clockwise)
S_PIVOT_X = 1
S_PIVOT_Y = 2
S_LINING_CENTRE_X = 3  # centre of the lining arc, m
S_LINING_CENTRE_Y = 4
S_LINING_RADIUS = 5
S_LINING_MID_ANGLE = 6  # polar angle of the arc's middle, seen from the arc centre, rad
S_LINING_HALF_ANGLE = 7
S_TIP_X = 8
S_TIP_Y = 9
S_ACTUATION_DIR_X = 10
S_ACTUATION_DIR_Y = 11
S_MASS = 12
S_MASS_CENTRE_X = 13
S_MASS_CENTRE_Y = 14
S_INERTIA = 15  # about the pivot, kg m^2
S_ACTUATION_GAIN = 16  # 2 x actuation share x (1 + actuation gain change / 100)
S_ENABLED = 17  # 0.0: shoe removed from the model (held retracted, no forces)
S_LINING_HALF_COS = 18  # cos and sin of the half angle, so the kernel needs no atan2
S_LINING_HALF_SIN = 19
S_LINING_MID_COS = 20  # unit vector toward the arc's middle at rest
S_LINING_MID_SIN = 21
S_FRICTION_COEFFICIENT = 22  # this shoe's lining: mu (1 + friction change / 100)
# the shoe's actuation (model/actuation.py shaped): its share and pressure factor (whose
# product, doubled, is S_ACTUATION_GAIN), a delay and first-order lag of the commanded
# history, s, and a pulsation (relative amplitude, frequency Hz); S_ACTUATION_SHAPED 1.0
# when any of delay, lag, pulsation or a weak return spring (below) is set (else the
# history is used as commanded)
S_SHARE = 23
S_PRESSURE_FACTOR = 24
S_ACTUATION_DELAY = 25
S_ACTUATION_LAG = 26
S_PULSATION_AMPLITUDE = 27
S_PULSATION_FREQUENCY = 28
S_ACTUATION_SHAPED = 29
# a weakened return spring (model/actuation.py spring_release): the preload it lost, N at
# the tip, and the healthy spring's hold margin over the residual line pressure, N
S_SPRING_RELEASE = 30
S_SPRING_MARGIN = 31

# drum out-of-roundness (model/defects.py DrumDefect), after the shoes: the number of
# harmonics, then (order k, amplitude m, phase rad) per harmonic; r(psi) = R0 +
# sum a cos(k psi + phase), psi the angle in the drum's frame (model/contact.py drum_radius)
P_DRUM_WAVE_COUNT = P_SHOE_BASE + 2 * SHOE_STRIDE
P_DRUM_WAVE_BASE = P_DRUM_WAVE_COUNT + 1
DRUM_WAVE_STRIDE = 3
W_ORDER = 0
W_AMPLITUDE = 1
W_PHASE = 2
MAX_DRUM_HARMONICS = 24  # most harmonics one drum carries (model/defects.py DrumDefect)

# nominal (healthy) geometry of the LEFT shoe, from which model/growth.py re-places a shoe
# whose pivot moves during the run (model/placement.py place_shoe's inputs)
P_NOMINAL_BASE = P_DRUM_WAVE_BASE + MAX_DRUM_HARMONICS * DRUM_WAVE_STRIDE
N_PIVOT_X = 0
N_PIVOT_Y = 1
N_TIP_X = 2
N_TIP_Y = 3
N_MASS_CENTRE_X = 4
N_MASS_CENTRE_Y = 5
N_INERTIA = 6  # about the nominal pivot, kg m^2
N_MASS = 7
N_LINING_MID = 8  # polar angle of the lining arc's middle, rad
N_POSE = 9  # the pose rule a moved pin places the shoe by (POSE_*)
NOMINAL_SIZE = 10
# pose rules (parameters.POSES, model/placement.py place_shoe)
POSE_TIP_ABUTMENT = 0
POSE_EYE_PISTON = 1

# defects that change during the run (model/defects.py Defects.growth): the number of
# entries, then per entry what it changes (G_KIND: a GK_* id, G_SHOE: 0 left, 1 right, -1
# the drum) and its law (catalogue.severity_at's arguments). Defects present from the
# start are packed into the slots above and have no entry.
P_GROWTH_COUNT = P_NOMINAL_BASE + NOMINAL_SIZE
P_GROWTH_BASE = P_GROWTH_COUNT + 1
GROWTH_STRIDE = 8
G_KIND = 0
G_SHOE = 1
G_LAW = 2
G_ONSET = 3
G_RATE = 4
G_START = 5
G_FINAL = 6
G_NOW = 7  # in the kernel's working copy: the severity last set (NaN: none yet)
MAX_GROWTH_ENTRIES = 16
GK_PIVOT = 0  # pivot_radius_change, %: the shoe is re-placed (placement.place_shoe)
GK_SHARE = 1  # actuation_share_change: this shoe's gain 2 (0.5 + s), the other's 2 (0.5 - s)
GK_DRUM = 2  # drum_out_of_round, um of peak runout: every harmonic scales with it
GK_FRICTION = 3  # friction_change, %: the shoe's lining coefficient (growth.lining_friction)
GK_GAIN = 4  # actuation_gain_change, %: the shoe's pressure factor (actuation.shoe_gain)
GK_PULSATION = 5  # actuation_pulsation, %: the shoe's pulsation amplitude
GK_WEAR = 6  # lining_wear, mm: the shoe's lining radius (growth.apply; friction work: its state)
GK_FLAT = 7  # drum_flat, um: the flat's depth

# lining wear per shoe (model/growth.py apply), after the growth entries: the lining's
# unworn radius, the thickness lost now and, for wear driven by friction work, the wear per
# joule of the shoe's friction work (0 before the onset and once the final wear is reached)
P_LINING_BASE = P_GROWTH_BASE + MAX_GROWTH_ENTRIES * GROWTH_STRIDE
LINING_STRIDE = 3
LN_RADIUS = 0  # the unworn lining's arc radius, m (S_LINING_RADIUS is it minus the wear)
LN_WEAR = 1  # thickness lost now, m
LN_WEAR_RATE = 2  # m of wear per J of this shoe's friction work (catalogue LAW_FRICTION_WORK)

# a local flat of the drum (model/defects.py DrumFlat, model/contact.py drum_radius): its
# depth (0: none), its centre in the drum's frame and its half width
P_FLAT_DEPTH = P_LINING_BASE + 2 * LINING_STRIDE  # m
P_FLAT_CENTRE = P_FLAT_DEPTH + 1  # rad, the angle psi of the drum's own frame
P_FLAT_HALF_WIDTH = P_FLAT_DEPTH + 2  # rad


# the vehicle around the brake (model/vehicle.py) and its drive cycle (model/cycle.py):
# P_DRIVEN 1.0 when road load and drive torque act on the flywheel (else the flywheel
# equation is the published one, with no external torque). Forces are this brake's share.
P_DRIVEN = P_FLAT_HALF_WIDTH + 1
P_WHEEL_RADIUS = P_DRIVEN + 1  # rolling radius, m: vehicle speed = flywheel speed x it
P_ROLLING_FORCE = P_DRIVEN + 2  # m_share g c_rr cos(grade), N (before the smoothed sign)
P_GRADE_FORCE = P_DRIVEN + 3  # m_share g sin(grade), N (uphill positive)
P_DRAG_FACTOR = P_DRIVEN + 4  # share x rho C_d A / 2, N s^2/m^2
P_ROLLING_SMOOTHING_SPEED = P_DRIVEN + 5  # width of the rolling resistance's sign, m/s
P_DRIVE_TORQUE = P_DRIVEN + 6  # in the kernel's working copy: the step's drive torque, N m
# the cycle: its segment count (0: no cycle, the actuation history commands the brake),
# the speed controller's limits, then per segment (kind, target speed rad/s, brake force
# N per shoe, duration s, the vehicle load factor range a hold sets, low and high; 0: the
# segment leaves the load as it is)
P_CYCLE_COUNT = P_DRIVEN + 7
P_CYCLE_MAX_DRIVE_TORQUE = P_DRIVEN + 8  # N m at the flywheel
P_CYCLE_TIME_CONSTANT = P_DRIVEN + 9  # speed controller's time constant, s
P_CYCLE_RISE = P_DRIVEN + 10  # brake force ramp on apply and release, s
P_CYCLE_MAX_FORCE = P_DRIVEN + 11  # drag segments' brake force limit, N per shoe
P_CYCLE_BASE = P_DRIVEN + 12
CYCLE_STRIDE = 6
Q_KIND = 0  # a SEG_* id
Q_SPEED = 1
Q_FORCE = 2
Q_DURATION = 3
Q_LOAD_LOW = 4  # the load factor a hold draws per stop within [low, high] (cycle.load_draw)
Q_LOAD_HIGH = 5
MAX_CYCLE_SEGMENTS = 64
SEG_ACCELERATE = 0  # drive to the target speed (speed controller, torque up to the max)
SEG_CRUISE = 1  # hold the target speed with the drive for the duration
SEG_BRAKE = 2  # brake force ramped to the segment's until the speed falls to the target
SEG_HOLD = 3  # keep the brake force for the duration
SEG_RELEASE = 4  # ramp the brake force to 0; no drive, for the duration
SEG_DRAG = 5  # hold the target speed with the brake (no drive) for the duration
SEG_END = 6  # after the last segment: no drive, the brake force kept
SEGMENT_KINDS = ("accelerate", "cruise", "brake", "hold", "release", "drag", "end")

# 1.0: after the last segment the cycle starts again at its first (else it ends: SEG_END)
P_CYCLE_REPEAT = P_CYCLE_BASE + MAX_CYCLE_SEGMENTS * CYCLE_STRIDE

# a live drive command of a run with a vehicle and no cycle (model/cycle.py LiveDrive):
# 1.0 while the speed controller drives toward P_LIVE_TARGET_SPEED (flywheel rad/s; its
# limits P_CYCLE_MAX_DRIVE_TORQUE and P_CYCLE_TIME_CONSTANT); else P_DRIVE_TORQUE holds
P_LIVE_SPEED_CONTROL = P_CYCLE_REPEAT + 1
P_LIVE_TARGET_SPEED = P_CYCLE_REPEAT + 2
# the key of the cycle's per-stop load draws (cycle.load_key of the run's seed): two 32-bit
# halves, high then low, each exact in a float64
P_CYCLE_LOAD_KEY = P_LIVE_TARGET_SPEED + 1


# the brake's temperature (model/thermal.py): P_THERMAL 1.0 when the run carries its thermal
# state (Y_BRAKE_TEMPERATURE); the temperature a run without one is recorded at, deg C; the
# fade law (thermal.fade_ratio's arguments); the linings' friction coefficients when cool,
# left then right (a growing friction change updates them); the thermal state's heat
# capacity J/K, its conductance to the air at rest W/K and per rad/s of the drum W s/K
# (per m/s of the vehicle times the wheel radius), and the air's temperature, deg C
P_THERMAL = P_CYCLE_LOAD_KEY + 2
P_HELD_TEMPERATURE = P_THERMAL + 1
P_FADE_ONSET = P_THERMAL + 2
P_FADE_FULL = P_THERMAL + 3
P_FADE_FULL_RATIO = P_THERMAL + 4
P_COOL_FRICTION = P_THERMAL + 5  # left; the right shoe's at + 1
P_HEAT_CAPACITY = P_THERMAL + 7
P_COOLING = P_THERMAL + 8
P_COOLING_PER_SPEED = P_THERMAL + 9
P_AMBIENT = P_THERMAL + 10

# the service brake (model/service.py; service_parameters.ServiceBrakeParameters): P_SERVICE 1.0
# when the brake has return springs and rest stops (else the study brake: none of the
# slots below is read); the residual line force under which the wheel cylinder never
# pushes, N; the rest stop's stiffness N/m and damping N s/m at the tip; then per shoe
# (left, then right at + SPRING_STRIDE) its spring's preload N and rate N/m as weakened,
# the tip travel at its rest angle (where the preload is), and where its stop engages, m
P_SERVICE = P_AMBIENT + 1
P_RESIDUAL_FORCE = P_SERVICE + 1
P_STOP_STIFFNESS = P_SERVICE + 2
P_STOP_DAMPING = P_SERVICE + 3
P_SPRING_BASE = P_SERVICE + 4
SPRING_STRIDE = 4
R_PRELOAD = 0  # N at the tip, the healthy preload times (1 - weakening)
R_RATE = 1  # N/m at the tip, the healthy rate times (1 - weakening)
R_REST_TRAVEL = 2  # tip travel (m, outward, from the tip's assembled place) at rest
R_STOP_TRAVEL = 3  # tip travel (m) below which the shoe presses on its stop

# the service brake's hydraulic circuit (model/service.py): the wheel-cylinder piston's
# area, m^2, the circuit's compliance seen from the wheel, m^3/Pa, and the line's flow
# resistance, Pa s/m^3 (the line pressure is the state Y_LINE_PRESSURE)
P_PISTON_AREA = P_SPRING_BASE + 2 * SPRING_STRIDE
P_LINE_COMPLIANCE = P_PISTON_AREA + 1
P_LINE_RESISTANCE = P_PISTON_AREA + 2
# the line's defects (catalogue location "line", model/line_kinds.py): the volume of air in
# the circuit at atmospheric pressure, m^3 (0: none; it adds an isothermal gas's
# compliance), and a leak's conductance to the reservoir, m^3/(s Pa) (0: none)
P_LINE_AIR_VOLUME = P_PISTON_AREA + 3
P_LINE_LEAK_CONDUCTANCE = P_PISTON_AREA + 4

# the service brake's tyre (model/tyre.py; service_parameters.TyreParameters), read when P_SERVICE:
# the LuGre law's presliding stiffness sigma0 1/m, its damping sigma1 s/m and viscous term
# sigma2 s/m (each per newton of the wheel's load), the road's friction coefficients of
# the Stribeck curve, sliding (a locked tyre's) and peak (at zero slip speed), and the
# curve's speed m/s and exponent. The rolling radius is P_WHEEL_RADIUS (the vehicle's, or
# the default one), the wheel's load the mass the flywheel stands for times g.
P_TYRE_STIFFNESS = P_LINE_LEAK_CONDUCTANCE + 1
P_TYRE_DAMPING = P_TYRE_STIFFNESS + 1
P_TYRE_VISCOUS = P_TYRE_STIFFNESS + 2
P_TYRE_SLIDING = P_TYRE_STIFFNESS + 3
P_TYRE_PEAK = P_TYRE_STIFFNESS + 4
P_TYRE_STRIBECK_SPEED = P_TYRE_STIFFNESS + 5
P_TYRE_STRIBECK_EXPONENT = P_TYRE_STIFFNESS + 6

# the service brake's lining contact distributed over the arc (model/lining.py), read when
# P_LINING_NODE_STIFFNESS > 0 (the study brake: 0, its point contact): the stiffness of
# one node of the arc's quadrature, N/m (the foundation's modulus E/t times the node's
# share of the lining's area), and its damping, N s/m
P_LINING_NODE_STIFFNESS = P_TYRE_STIFFNESS + 7
P_LINING_NODE_DAMPING = P_TYRE_STIFFNESS + 8
# the service brake's self-adjuster stepping within the run (model/ratchet.py): each shoe's
# ratchet step at the lining, m (left; the right shoe's at + 1; 0: no ratchet within the
# run: the study brake, a seized adjuster, a wear that does not grow), and the strut's free
# play at the lining, m (the new lining's running clearance)
P_ADJUSTER_STEP = P_TYRE_STIFFNESS + 9
P_ADJUSTER_FREE_PLAY = P_TYRE_STIFFNESS + 11

N_PARAMS = P_TYRE_STIFFNESS + 12

# --- state vector ---------------------------------------------------------------------
Y_FLYWHEEL_ANGLE = 0
Y_DRUM_ANGLE = 1
Y_LEFT_ANGLE = 2
Y_RIGHT_ANGLE = 3
Y_FLYWHEEL_SPEED = 4
Y_DRUM_SPEED = 5
Y_LEFT_SPEED = 6
Y_RIGHT_SPEED = 7
# energy quadratures, J, integrated with the motion
Y_FRICTION_WORK = 8
Y_COUPLING_DAMPER_LOSS = 9
Y_CONTACT_LOSS = 10
Y_ACTUATION_WORK = 11
Y_DRIVE_WORK = 12  # work of the drive torque on the flywheel (0 without P_DRIVEN)
Y_ROAD_LOAD_WORK = 13  # work of the flywheel against the road load (0 without P_DRIVEN)
N_STATE = 14
# the lining wear of a shoe that wears with its friction work (catalogue LAW_FRICTION_WORK),
# m, integrated with the motion from its onset: only a run with such a wear carries these
# two states (N_STATE_WEAR), so every other run steps exactly the N_STATE above
Y_LEFT_WEAR = 14
Y_RIGHT_WEAR = 15
N_STATE_WEAR = 16
# the brake's temperature, deg C (model/thermal.py): only a run with a [thermal] table
# carries it, after the two wear states (which stay 0 unless a lining wears with work)
Y_BRAKE_TEMPERATURE = 16
N_STATE_THERMAL = 17
# the service brake's states (P_SERVICE): a service run always carries all N_STATE_SERVICE
# of them, so its wear slots (0 unless a lining wears with work) and its temperature slot
# (held at P_HELD_TEMPERATURE, its rate 0, unless the run has a thermal state: P_THERMAL)
# are there on every service run. The tyre's deflection, m (reserved: rate 0 until a tyre
# is modelled), and the line pressure at the wheel cylinder, Pa.
Y_TYRE_DEFLECTION = 17
Y_LINE_PRESSURE = 18
N_STATE_SERVICE = 19

# --- recorded sample columns -------------------------------------------------------------
COLUMNS: tuple[str, ...] = (
    "time_s",
    "flywheel_angle_rad",
    "drum_angle_rad",
    "left_angle_rad",
    "right_angle_rad",
    "flywheel_speed_rad_s",
    "drum_speed_rad_s",
    "left_speed_rad_s",
    "right_speed_rad_s",
    "left_indentation_m",
    "right_indentation_m",
    "left_normal_force_n",
    "right_normal_force_n",
    "left_friction_force_n",
    "right_friction_force_n",
    "left_actuation_force_n",
    "right_actuation_force_n",
    "left_pivot_fx_n",
    "left_pivot_fy_n",
    "right_pivot_fx_n",
    "right_pivot_fy_n",
    "left_contact_x_m",
    "left_contact_y_m",
    "right_contact_x_m",
    "right_contact_y_m",
    "friction_work_j",
    "coupling_damper_loss_j",
    "contact_loss_j",
    "actuation_work_j",
    "lock_loss_j",
    "regime",
    "left_regime",
    "right_regime",
    "left_indentation_rate_m_s",
    "right_indentation_rate_m_s",
    "left_sliding_speed_m_s",
    "right_sliding_speed_m_s",
    "drum_sticking",  # 1.0 while static friction holds the drum at standstill, else 0.0
    "left_lining_wear_m",  # lining thickness lost, as the physics step of the sample has it
    "right_lining_wear_m",
    "drive_torque_n_m",  # on the flywheel, this brake's share of the traction (model/cycle.py)
    "road_load_torque_n_m",  # against the flywheel's motion (model/vehicle.py)
    "drive_work_j",
    "road_load_work_j",
    "cycle_segment",  # the drive cycle's segment index (its kind: P_CYCLE_*); -1: no cycle
    "brake_temperature_c",  # the thermal state's, or the temperature the run is held at
    "flywheel_inertia_kg_m2",  # in force: a cycle's hold may change the load (model/cycle.py)
    "load_change_work_j",  # kinetic energy the load changes brought, 0.5 dI w_f^2 summed
)
COL = {name: i for i, name in enumerate(COLUMNS)}
N_COLUMNS = len(COLUMNS)

# Column indices for the compiled kernels, which cannot look names up (numba reads these
# module constants at compile time). Left-shoe columns; the right shoe's follow at the
# offsets given by RIGHT_OF (each per-shoe pair is written left, right).
C_TIME = COL["time_s"]
C_STATE = COL["flywheel_angle_rad"]  # first of the 8 state columns, in layout.Y_* order
C_INDENTATION = COL["left_indentation_m"]
C_NORMAL_FORCE = COL["left_normal_force_n"]
C_FRICTION_FORCE = COL["left_friction_force_n"]
C_ACTUATION_FORCE = COL["left_actuation_force_n"]
C_PIVOT_FX = COL["left_pivot_fx_n"]  # fx, fy of the left shoe, then of the right
C_PIVOT_FY = COL["left_pivot_fy_n"]
C_CONTACT_X = COL["left_contact_x_m"]  # x, y of the left shoe, then of the right
C_CONTACT_Y = COL["left_contact_y_m"]
C_ENERGY = COL["friction_work_j"]  # first of the 4 energy quadratures, in Y_* order
C_LOCK_LOSS = COL["lock_loss_j"]
C_REGIME = COL["regime"]
C_SHOE_REGIME = COL["left_regime"]
C_INDENTATION_RATE = COL["left_indentation_rate_m_s"]
C_SLIDING_SPEED = COL["left_sliding_speed_m_s"]
C_DRUM_STICKING = COL["drum_sticking"]
C_LINING_WEAR = COL["left_lining_wear_m"]
C_DRIVE_TORQUE = COL["drive_torque_n_m"]
C_ROAD_LOAD_TORQUE = COL["road_load_torque_n_m"]
C_DRIVE_WORK = COL["drive_work_j"]
C_ROAD_LOAD_WORK = COL["road_load_work_j"]
C_PHASE = COL["cycle_segment"]
C_BRAKE_TEMPERATURE = COL["brake_temperature_c"]
C_FLYWHEEL_INERTIA = COL["flywheel_inertia_kg_m2"]
C_LOAD_CHANGE_WORK = COL["load_change_work_j"]
RIGHT_OF_SCALAR = 1  # right-shoe column = left-shoe column + 1 for scalar per-shoe pairs
RIGHT_OF_VECTOR = 2  # right-shoe (x, y) columns = left-shoe ones + 2

# --- regimes ---------------------------------------------------------------------------
REGIME_FREE = 0  # not touching the drum (not yet, or released)
REGIME_IMPACTING = 1  # striking and bouncing off the drum
REGIME_CONTACT = 2  # riding steadily on the drum
REGIME_STOPPED = 3  # drum at standstill, held by static friction (model/standstill.py)
REGIME_NAMES = ("free", "impacting", "contact", "stopped")

# --- kernel bookkeeping (int64 array carried between calls) -------------------------------
K_STUCK = 0  # 1 while static friction holds the drum (model/standstill.py)
K_LEFT_REGIME = 1
K_RIGHT_REGIME = 2
K_LEFT_IN_CONTACT = 3
K_RIGHT_IN_CONTACT = 4
K_LEFT_LAST_CHANGE_STEP = 5  # step index at which the contact flag last changed
K_RIGHT_LAST_CHANGE_STEP = 6
K_STATUS = 7  # 0 running, 1 non-finite state
K_BREAKAWAYS = 8  # stick -> slip transitions so far
K_SEGMENT = 9  # the drive cycle's current segment (model/cycle.py); P_CYCLE_COUNT: ended
K_LOAD_DRAWS = 10  # the cycle's per-stop load draws so far: the next draw's number
N_KSTATE = 11

# float bookkeeping carried between calls (fstate)
F_STOP_TIME = 0  # instant the vehicle came to rest (standstill.at_rest), s; < 0 until then
F_LOCK_LOSS = 1  # kinetic energy removed at stick instants, J
F_SWITCHES = 2  # contact switches located inside steps (rk4-located)
F_WHEEL_LOCK_TIME = 3  # instant the drum first stuck, s; < 0 until then
# the drive cycle's controller (model/cycle.py): when the segment began, s; the brake
# force ramp in force (from F_RAMP_T0, F_RAMP_F0 to F_RAMP_T1, F_RAMP_F1: s, N per shoe);
# the drag segment's integrated brake force, N
F_SEGMENT_START = 4
F_RAMP_T0 = 5
F_RAMP_F0 = 6
F_RAMP_T1 = 7
F_RAMP_F1 = 8
F_DRAG_FORCE = 9
# the cycle's vehicle load factor in force (over the packed flywheel inertia's; set to 1
# when the cycle starts) and the kinetic energy its changes brought, J (model/cycle.py)
F_LOAD_FACTOR = 10
F_LOAD_CHANGE_WORK = 11
# the self-adjuster within the run (model/ratchet.py), whole teeth per shoe (left; right at
# + 1): taken up (in the lining's radius) and picked up by an application, not yet taken
# up (the shoe has not returned to the lengthened strut yet)
F_ADJUSTER_TAKEN = 12
F_ADJUSTER_PENDING = 14
N_FSTATE = 16

# contact modes of the right-hand side (the adaptive reference forces them per segment)
CONTACT_AUTO = -1
CONTACT_OFF = 0
CONTACT_ON = 1

# fixed-step schemes of the compiled stepper (advance.fixed_step_advance)
SCHEME_RK4 = 0  # classical RK4, contact switched wherever a stage falls
SCHEME_RK4_LOCATED = 1  # RK4 with contact onsets and separations located inside the step
SCHEME_SEMI_IMPLICIT_EULER = 2  # symplectic (semi-implicit) Euler: speeds first, then angles
MAX_SWITCHES_PER_STEP = 8  # located contact switches per step; further ones are not located
