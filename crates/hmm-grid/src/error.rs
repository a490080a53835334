//! The error type of hmm-grid.

/// What can go wrong building or using a hidden Markov model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// An error from the shared model, and a configuration value out of range
    /// ([`tracker_model::Error::InvalidParameter`]).
    #[error(transparent)]
    Model(#[from] tracker_model::Error),
    /// A probability vector or matrix row is invalid.
    #[error("{what} row {row}: {reason}")]
    InvalidRow {
        /// Which parameter ("initial distribution", "transition matrix", "emission matrix").
        what: &'static str,
        /// The row (0 for the initial distribution).
        row: usize,
        /// What is wrong, with the values.
        reason: String,
    },
    /// Sizes that do not fit together.
    #[error("{what}: expected {expected}, got {got}")]
    ShapeMismatch {
        /// What was counted, e.g. "emission matrix entries (N × M)".
        what: &'static str,
        /// The count the other inputs imply.
        expected: usize,
        /// The count given.
        got: usize,
    },
    /// A matrix whose entry count rows × cols does not fit in `usize`.
    #[error("{what}: {rows} × {cols} entries overflow the address space")]
    SizeOverflow {
        /// Which matrix.
        what: &'static str,
        /// Rows asked for.
        rows: usize,
        /// Columns asked for.
        cols: usize,
    },
    /// An observation symbol outside 0..M.
    #[error(
        "observation {index} of sequence {sequence} is symbol {symbol}, but the model has {n_symbols} symbols"
    )]
    SymbolOutOfRange {
        /// Which sequence (0 for a single one).
        sequence: usize,
        /// Position in the sequence.
        index: usize,
        /// The symbol.
        symbol: usize,
        /// M.
        n_symbols: usize,
    },
    /// An empty input where data is needed.
    #[error("{0} is empty")]
    Empty(&'static str),
    /// The observations have probability zero under the model (every path is impossible).
    #[error("observation {index} of sequence {sequence} has probability 0 under the model")]
    ImpossibleObservation {
        /// Which sequence.
        sequence: usize,
        /// Position of the first impossible observation.
        index: usize,
    },
    /// A cell (column, row) outside the grid a state space was built from.
    #[error("cell ({col}, {row}) is outside the {n_cols}×{n_rows} grid")]
    CellOutsideGrid {
        /// The column asked for.
        col: usize,
        /// The row asked for.
        row: usize,
        /// Columns of the grid.
        n_cols: usize,
        /// Rows of the grid.
        n_rows: usize,
    },
    /// A grid operation on a state space built from a road graph.
    #[error("the state space is a road graph, not a cell grid")]
    NotAGrid,
}

/// Result with hmm-grid's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// A configuration value out of range, as tracker-model's parameter checks report it.
pub(crate) fn invalid_parameter(name: &'static str, reason: String) -> Error {
    Error::Model(tracker_model::Error::InvalidParameter { name, reason })
}
