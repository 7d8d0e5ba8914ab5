//! ID lists as people write them: "1-5,9, 12-14".

/// Most IDs one list may name: a sheet or scene of this many is already far
/// beyond any swarm, and the bound keeps `1-4000000000` from filling memory.
pub const MAX_LISTED_IDS: usize = 100_000;

/// Why an ID list was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum IdListError {
    #[error("'{0}' names ID 0, which means \"unknown\"; IDs start at 1")]
    /// An item names ID 0.
    ZeroId(String),
    #[error("'{0}' is not an ID or a range like 3-7")]
    /// An item is neither an ID nor a range.
    NotAnId(String),
    #[error("range '{0}' runs backwards")]
    /// A range whose end is below its start.
    Backwards(String),
    #[error("range '{0}' names more than {MAX_LISTED_IDS} IDs")]
    /// A range longer than the list may be.
    RangeTooLong(String),
    #[error("the list names more than {MAX_LISTED_IDS} IDs")]
    /// The whole list names too many IDs.
    TooMany,
    #[error("no IDs given")]
    /// The list is empty.
    Empty,
    #[error("ID {0} is listed more than once")]
    /// An ID appears twice.
    Repeated(u32),
}

/// Parses lists like "1-5,9, 12-14" in the order written. An ID named twice
/// is refused: a sheet printing it twice would make the manifest's
/// marker-to-ID match, and so validation, ambiguous.
pub fn parse_id_list(text: &str) -> Result<Vec<u32>, IdListError> {
    let mut ids = Vec::new();
    for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let parse = |s: &str| match s.trim().parse::<u32>() {
            Ok(0) => Err(IdListError::ZeroId(part.to_string())),
            Ok(id) => Ok(id),
            Err(_) => Err(IdListError::NotAnId(part.to_string())),
        };
        match part.split_once('-') {
            Some((a, b)) => {
                let (a, b) = (parse(a)?, parse(b)?);
                if a > b {
                    return Err(IdListError::Backwards(part.to_string()));
                }
                if (b - a) as usize >= MAX_LISTED_IDS {
                    return Err(IdListError::RangeTooLong(part.to_string()));
                }
                ids.extend(a..=b);
            }
            None => ids.push(parse(part)?),
        }
        if ids.len() > MAX_LISTED_IDS {
            return Err(IdListError::TooMany);
        }
    }
    check_id_list(&ids)?;
    Ok(ids)
}

/// The rules [`parse_id_list`] applies, for lists that arrive already as
/// numbers (the Python and web front ends): not empty, no ID 0, at most
/// [`MAX_LISTED_IDS`], none twice.
pub fn check_id_list(ids: &[u32]) -> Result<(), IdListError> {
    if ids.is_empty() {
        return Err(IdListError::Empty);
    }
    if ids.contains(&0) {
        return Err(IdListError::ZeroId("0".to_string()));
    }
    if ids.len() > MAX_LISTED_IDS {
        return Err(IdListError::TooMany);
    }
    let mut sorted = ids.to_vec();
    sorted.sort_unstable();
    if let Some(pair) = sorted.windows(2).find(|w| w[0] == w[1]) {
        return Err(IdListError::Repeated(pair[0]));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::parse_id_list;

    #[test]
    fn id_lists_take_ranges_and_single_ids_in_order() {
        assert_eq!(
            parse_id_list("1-5,9, 12-14").unwrap(),
            [1, 2, 3, 4, 5, 9, 12, 13, 14]
        );
        assert_eq!(parse_id_list("7,2").unwrap(), [7, 2]);
    }

    #[test]
    fn bad_id_lists_get_plain_messages() {
        let error = |text: &str| parse_id_list(text).unwrap_err().to_string();
        assert!(error("5-3").contains("backwards"));
        assert_eq!(error("1,x"), "'x' is not an ID or a range like 3-7");
        assert!(error("-3").contains("'-3' is not an ID"));
        assert!(error("0").contains("IDs start at 1"));
        assert!(error("1-3,2").contains("ID 2 is listed more than once"));
        assert!(error("1-4000000000").contains("more than 100000 IDs"));
        assert!(error(" , ").contains("no IDs given"));
    }
}
