//! Per-move side tables: analysis results keyed by the move they belong to.

/// A move's address in a program: operation index and move index.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
pub struct MoveRef {
    pub op: u32,
    pub mv: u32,
}

impl MoveRef {
    pub fn new(op: usize, mv: usize) -> MoveRef {
        MoveRef {
            op: op as u32,
            mv: mv as u32,
        }
    }
}

/// Values for some moves of a program, in program order, at most one per move
/// (an analysis's results: the contact of every cutting point, the working
/// diameter, a gouge depth). Looked up by [`MoveRef`] or walked in order.
#[derive(Clone, Debug, PartialEq)]
pub struct MoveTable<T> {
    keys: Vec<MoveRef>,
    values: Vec<T>,
}

impl<T> Default for MoveTable<T> {
    fn default() -> Self {
        MoveTable {
            keys: Vec::new(),
            values: Vec::new(),
        }
    }
}

/// A key pushed out of program order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("move table keys must increase: {0:?} after {1:?}")]
pub struct OutOfOrder(pub MoveRef, pub MoveRef);

impl<T> MoveTable<T> {
    pub fn new() -> MoveTable<T> {
        MoveTable::default()
    }

    /// A table from keys in program order and their values.
    pub fn from_parts(keys: Vec<MoveRef>, values: Vec<T>) -> Result<MoveTable<T>, OutOfOrder> {
        if let Some(w) = keys.windows(2).find(|w| w[0] >= w[1]) {
            return Err(OutOfOrder(w[1], w[0]));
        }
        assert_eq!(keys.len(), values.len(), "one value per key");
        Ok(MoveTable { keys, values })
    }

    /// Appends the value of a move after every move already in the table.
    pub fn push(&mut self, key: MoveRef, value: T) -> Result<(), OutOfOrder> {
        if let Some(&last) = self.keys.last() {
            if key <= last {
                return Err(OutOfOrder(key, last));
            }
        }
        self.keys.push(key);
        self.values.push(value);
        Ok(())
    }

    pub fn get(&self, key: MoveRef) -> Option<&T> {
        self.keys.binary_search(&key).ok().map(|i| &self.values[i])
    }

    pub fn len(&self) -> usize {
        self.keys.len()
    }

    pub fn is_empty(&self) -> bool {
        self.keys.is_empty()
    }

    pub fn keys(&self) -> &[MoveRef] {
        &self.keys
    }

    pub fn values(&self) -> &[T] {
        &self.values
    }

    pub fn values_mut(&mut self) -> &mut [T] {
        &mut self.values
    }

    pub fn iter(&self) -> impl ExactSizeIterator<Item = (MoveRef, &T)> {
        self.keys.iter().copied().zip(self.values.iter())
    }

    /// The same keys with each value mapped.
    pub fn map<U>(&self, f: impl FnMut(&T) -> U) -> MoveTable<U> {
        MoveTable {
            keys: self.keys.clone(),
            values: self.values.iter().map(f).collect(),
        }
    }

    /// The rows of operation `op`: its keys and values.
    pub fn of_op(&self, op: usize) -> (&[MoveRef], &[T]) {
        let op = op as u32;
        let lo = self.keys.partition_point(|k| k.op < op);
        let hi = self.keys.partition_point(|k| k.op <= op);
        (&self.keys[lo..hi], &self.values[lo..hi])
    }

    pub fn into_parts(self) -> (Vec<MoveRef>, Vec<T>) {
        (self.keys, self.values)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_stay_in_program_order_and_look_up() {
        let mut t = MoveTable::new();
        t.push(MoveRef::new(0, 3), 'a').expect("first");
        t.push(MoveRef::new(1, 0), 'b').expect("later op");
        assert!(t.push(MoveRef::new(0, 9), 'c').is_err());
        assert!(t.push(MoveRef::new(1, 0), 'c').is_err());
        assert_eq!(t.get(MoveRef::new(1, 0)), Some(&'b'));
        assert_eq!(t.get(MoveRef::new(0, 4)), None);
        assert_eq!(t.of_op(1).1, &['b']);
        assert!(
            MoveTable::from_parts(vec![MoveRef::new(0, 2), MoveRef::new(0, 1)], vec![1, 2])
                .is_err()
        );
    }
}
