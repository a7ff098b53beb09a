/* index.js - carries the access token (if the page was opened with one, PALP.token()) into the links. */
"use strict";
(function () {
  for (const id of ["link-dashboard", "link-trainee"]) {
    const a = document.getElementById(id);
    a.href = PALP.withToken(a.getAttribute("href")); /* the page it opens takes it out of its address */
  }
  PALP.connect({});
})();
