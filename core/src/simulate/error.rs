//! What can go wrong in a simulation: bad settings, a campaign the true arm
//! cannot perform, files that cannot be read or written.

use crate::error::{InputError, quoted};
use crate::kernel::KernelError;

/// An error of the campaign simulator. Settings errors name the setting (its
/// key in `campaign.toml`); file errors name the file, line and field.
///
/// ```
/// use aacmm_core::simulate::SimError;
/// let e = SimError::setting("poses_per_socket", "at least 3 touches per socket, got 2");
/// assert_eq!(
///     e.to_string(),
///     "setting `poses_per_socket`: at least 3 touches per socket, got 2"
/// );
/// ```
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A setting out of range or inconsistent with another.
    #[error("setting `{name}`: {message}")]
    Setting {
        /// The setting's key in `campaign.toml`.
        name: String,
        /// What is wrong and what is expected.
        message: String,
    },
    /// The error model does not fit the nominal arm.
    #[error("error model: {0}")]
    Model(String),
    /// The kernel cannot evaluate the arm (joint count).
    #[error(transparent)]
    Kernel(#[from] KernelError),
    /// Fewer well-separated socket positions than asked for could be found.
    #[error(
        "could place only {placed} of {wanted} sockets at least {min_separation_mm:.1} mm apart \
         in the arm's comfortable volume; ask for fewer sockets"
    )]
    SocketsNotPlaced {
        /// Sockets asked for.
        wanted: usize,
        /// Sockets placed.
        placed: usize,
        /// The minimum separation, mm.
        min_separation_mm: f64,
    },
    /// One socket could not be touched in enough distinct articulations.
    #[error(
        "socket {}: found {found} of {wanted} distinct poses (at least \
         {min_separation_deg}° apart in some joint, within joint limits) in {attempts} \
         inverse-kinematics starts; the socket may be out of reach or too close to the edge \
         of the workspace",
        quoted(socket)
    )]
    TooFewPoses {
        /// The socket's label.
        socket: String,
        /// Poses asked for.
        wanted: usize,
        /// Distinct poses found.
        found: usize,
        /// Inverse-kinematics starts tried.
        attempts: usize,
        /// The minimum pose separation, degrees.
        min_separation_deg: f64,
    },
    /// A file could not be read, parsed or written.
    #[error(transparent)]
    Input(#[from] InputError),
}

impl SimError {
    /// A [`SimError::Setting`] error (its message bounded as every message
    /// of the library is: `crate::error::MAX_MESSAGE`).
    pub fn setting(name: impl Into<String>, message: impl Into<String>) -> SimError {
        SimError::Setting {
            name: name.into(),
            message: crate::error::bounded(message.into()),
        }
    }
}
