+!g <- .print("café").
