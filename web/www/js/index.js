/* index.js - carries the access token (if the page was opened with one) into the links. */
"use strict";
(function () {
  const token = PALP.params().get("token");
  if (token) {
    for (const id of ["link-dashboard", "link-trainee"]) {
      const a = document.getElementById(id);
      a.href = a.getAttribute("href") + "?token=" + encodeURIComponent(token);
    }
  }
  PALP.connect({});
})();
