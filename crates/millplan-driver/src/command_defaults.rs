//! The value each command takes for an option the user does not give, one
//! submodule per command (the job's own defaults are in [`crate::defaults`]).
//! The binary names these constants in its argument declarations, so
//! `--help` prints them, and holds no number of its own.

/// Cutting data of the commands that evaluate spindle control along the way
/// (`speed`, `reorder`, `directions`, …): the thesis's test conditions.
pub mod cutting {
    /// Cutting speed, m/min.
    pub const VC: f64 = 63.0;
    /// Feed per tooth, mm.
    pub const FZ: f64 = 0.125;
    /// Flutes.
    pub const FLUTES: u32 = 2;
    /// Stock thickness along the surface normal, mm.
    pub const AP: f64 = 0.3;
}

/// `millplan speed`.
pub mod speed {
    /// A new S is written only when the speed changes by more than this, 1/min.
    pub const S_THRESHOLD: f64 = 1.0;
}

/// `millplan cut`.
pub mod cut {
    /// Flutes.
    pub const FLUTES: usize = 4;
    /// Helix angle, degrees.
    pub const HELIX_DEG: f64 = 30.0;
    /// Lead and tilt, degrees.
    pub const LEAD_DEG: f64 = 0.0;
    pub const TILT_DEG: f64 = 0.0;
    /// Gauge length without `--stickout`, in tool diameters.
    pub const STICKOUT_PER_D: f64 = 3.0;
    /// The force model's largest slice height, mm, rotation step, degrees,
    /// and the tool's Young's modulus, N/mm²: `feed`'s (the binary's
    /// `ForceModel` group declares them once for both; the Python binding
    /// names them here).
    pub const DZ: f64 = super::feed::DZ;
    pub const DPHI_DEG: f64 = super::feed::DPHI_DEG;
    pub const MODULUS: f64 = super::feed::MODULUS;
}

/// `millplan feed` and `millplan force` (and the force model's tool and
/// steps of `millplan cut`: `MODULUS`, `DZ`, `DPHI_DEG`).
pub mod feed {
    /// Flutes.
    pub const FLUTES: usize = 2;
    /// Helix angle, degrees.
    pub const HELIX_DEG: f64 = 30.0;
    /// Dexel size of the stock, mm.
    pub const RESOLUTION: f64 = 0.1;
    /// Largest axial slice height of the force model, mm.
    pub const DZ: f64 = 0.05;
    /// Largest rotation step of the force model, degrees.
    pub const DPHI_DEG: f64 = 1.0;
    /// Young's modulus of the tool (carbide), N/mm².
    pub const MODULUS: f64 = millplan_models::force::deflect::E_CARBIDE;
    /// Smallest feed per tooth, mm.
    pub const FZ_MIN: f64 = 0.01;
    /// Factor of safety on power, torque and stress.
    pub const FOS: f64 = 1.0;
}

/// `millplan raster`.
pub mod raster {
    /// Feed direction, degrees from +X.
    pub const ANGLE_DEG: f64 = 0.0;
    /// Margin inside the part's XY bounds, mm.
    pub const BOUNDARY: f64 = 0.0;
    /// Chord tolerance of the adaptive refinement, mm.
    pub const TOL: f64 = 0.002;
    /// Clearance above the part for rapids, mm.
    pub const CLEARANCE: f64 = 5.0;
    /// Cutting feed, mm/min.
    pub const FEED: f64 = 1500.0;
    /// Spindle speed, 1/min.
    pub const SPINDLE: f64 = 6000.0;
}

/// `millplan simulate`.
pub mod simulate {
    /// Dexel size, mm.
    pub const RESOLUTION: f64 = 0.1;
    /// Depth that counts as a collision or a gouge, mm.
    pub const TOL: f64 = 0.01;
}

/// `millplan gouge`.
pub mod gouge {
    /// Depth that counts as a gouge, mm.
    pub const TOL: f64 = 0.005;
    /// Sampling step along the moves, mm.
    pub const STEP: f64 = 0.1;
}

/// `millplan post`.
pub mod post {
    /// How far the tip may leave the CL segment, mm.
    pub const TOL: f64 = 0.01;
}

/// `millplan reorder`.
pub mod reorder {
    /// Seed of the random start.
    pub const SEED: u64 = 1;
    /// Fewest candidates of the paper's search.
    pub const N_MIN: usize = 4;
    /// D_w differences within this are ties, mm.
    pub const TIE: f64 = 0.001;
    /// A step changing D_w by more than this makes the search look farther, mm.
    pub const MAX_STEP: f64 = 0.5;
}

/// `millplan orient`.
pub mod orient {
    /// Lead range, degrees.
    pub const LEAD_RANGE: &str = "0:30";
    /// Tilt range, degrees.
    pub const TILT_RANGE: &str = "-30:30";
    /// Feed per tooth of the force evaluation, mm.
    pub const FZ: f64 = 0.1;
    /// Flutes.
    pub const FLUTES: usize = 2;
    /// Helix angle, degrees.
    pub const HELIX_DEG: f64 = 30.0;
    /// Axial depth and stepover of the evaluated engagement, mm.
    pub const AP: f64 = 0.5;
    pub const AE: f64 = 0.5;
    /// Dexel size of the stock, mm.
    pub const RESOLUTION: f64 = 0.1;
    /// Most sample moves per operation on the stock.
    pub const SAMPLES: usize = 48;
    /// The shank's reach from the ball centre to the holder, mm.
    pub const REACH: f64 = 30.0;
}

/// `millplan directions`.
pub mod directions {
    /// Stepover and point spacing of the generated rasters, mm.
    pub const STEPOVER: f64 = 1.0;
    pub const STEP: f64 = 0.5;
}

/// `millplan setup`.
pub mod setup {
    /// Approximate number of cells of the sphere's grid of directions.
    pub const CELLS: usize = 1200;
    /// How far a direction must leave a facet's surface, degrees.
    pub const CLEARANCE_DEG: f64 = 0.0;
}

/// `millplan tool`.
pub mod tool {
    /// Setup tolerance between presetter and first measurement, mm.
    pub const SETUP_TOL: f64 = 0.02;
    /// Clearance height above the laser, mm.
    pub const CLEARANCE: f64 = 100.0;
}

/// `millplan sweep`.
pub mod sweep {
    /// Tool diameters, mm.
    pub const D: &str = "6,8,10";
    /// Depths of cut, mm.
    pub const AP: &str = "0.1,0.25,0.5,0.75,1.0";
    /// Stepover to the machined neighbour, mm.
    pub const AE: &str = "1";
    /// Inclinations, degrees.
    pub const ALPHA: &str = "0,10,20,30,45,60";
    /// Feed-direction step, degrees.
    pub const AF_STEP: f64 = 5.0;
}

/// `millplan robot compensate` and `robot place`.
pub mod robot {
    /// Distance between the commanded points of a compensated path, mm
    /// (paper 001's spacing).
    pub const SPACING_MM: f64 = 0.3;
    /// Motions per KRL sub-program.
    pub const MAX_POINTS: usize = 5000;
    /// The box the workpiece origin may be placed in, mm in the robot base.
    pub const PLACE_BOX: &str = "800,-800,0,1800,800,800";
    /// Seed of the placement search.
    pub const SEED: u64 = 1;
    /// Independent runs of the placement search.
    pub const RESTARTS: usize = 4;
}

/// When a command's work is long enough to show its progress.
pub mod progress {
    /// Moves of a program from which `speed` and `reorder` show their
    /// phases (some 100,000 points a second at the least).
    pub const LONG_PROGRAM_MOVES: usize = 100_000;
    /// Strokes from which `simulate` shows its progress.
    pub const LONG_SIMULATION_STROKES: usize = 50_000;

    /// Whether `program` is long enough for `speed` and `reorder` to show
    /// their phases.
    pub fn long_program(program: &millplan_nc::Program) -> bool {
        program.move_count() >= LONG_PROGRAM_MOVES
    }
}
